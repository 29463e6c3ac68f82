#include "engine/representation.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace sirl {

Representation reference_representation(Method m, const Dataset& d) {
  if (!is_reference(m))
    throw std::invalid_argument(std::string("'") + method_name(m) + "' is not a reference");
  Representation r;
  r.method = m;
  r.shape.widths = {d.input_dim, m == Method::truth ? d.feature_count() : d.input_dim};
  return r;
}

Representation table_representation(std::vector<float> table, int64_t T, int d, int input_dim) {
  if (d < 1 || T < 1)
    throw std::invalid_argument("an external embedding needs T >= 1 rows of d >= 1 values, got [" +
                                std::to_string(T) + ", " + std::to_string(d) + "]");
  if (table.size() != size_t(T) * size_t(d))
    throw std::invalid_argument("an external embedding [" + std::to_string(T) + ", " +
                                std::to_string(d) + "] needs " + std::to_string(T * d) +
                                " values, got " + std::to_string(table.size()));
  for (size_t i = 0; i < table.size(); ++i)
    if (!std::isfinite(table[i]))
      throw std::invalid_argument("an external embedding holds " + std::to_string(table[i]) +
                                  " at row " + std::to_string(i / size_t(d)) + ", column " +
                                  std::to_string(i % size_t(d)) + " (every value must be finite)");
  Representation r;
  r.method = Method::external;
  r.shape.widths = {input_dim, d};
  r.table = std::move(table);
  return r;
}

MlpShape phi_shape(int in, const Hyper& h) {
  MlpShape s;
  s.widths.push_back(in);
  for (int w : h.phi_hidden) s.widths.push_back(w);
  s.widths.push_back(h.embedding_dim);
  s.relu_on_output = h.phi_relu_output;
  s.bf16_products = bf16_products(h);
  validate(s);
  return s;
}

void embed(const Representation& rep, const float* X, int64_t n, float* out, int threads) {
  if (rep.is_table())
    throw std::logic_error("embed: an external representation has no weights to apply");
  constexpr int64_t kChunk = 1024;
  MlpTape<float> tape;
  const int in = rep.shape.in(), d = rep.dim();
  for (int64_t i0 = 0; i0 < n; i0 += kChunk) {
    const int b = int(std::min(kChunk, n - i0));
    mlp_forward(rep.shape, rep.params.data(), X + i0 * in, b, tape, threads);
    std::copy(tape.output(), tape.output() + size_t(b) * d, out + i0 * d);
  }
}

std::vector<float> embed_rows(const Representation& rep, const Dataset& d,
                              const std::vector<int32_t>& rows, int threads) {
  const int dim = rep.dim();
  std::vector<float> out(rows.size() * size_t(dim));
  if (is_reference(rep.method)) {
    const float* src = rep.method == Method::truth ? d.features.data() : d.inputs.data();
    const int w = rep.method == Method::truth ? d.feature_count() : d.input_dim;
    if (w != dim)
      throw std::invalid_argument(std::string("the ") + method_name(rep.method) + " reference is " +
                                  std::to_string(dim) + " wide, the dataset's " +
                                  std::to_string(w));
    for (size_t i = 0; i < rows.size(); ++i)
      std::copy_n(src + ptrdiff_t(rows[i]) * dim, dim, out.begin() + i * dim);
    return out;
  }
  if (!rep.table.empty()) {
    if (rep.table.size() != size_t(d.count) * size_t(dim))
      throw std::invalid_argument("φ(Ξ) holds " + std::to_string(rep.table.size() / size_t(dim)) +
                                  " rows of " + std::to_string(dim) + ", the dataset " +
                                  std::to_string(d.count) + " trajectories");
    for (size_t i = 0; i < rows.size(); ++i)
      std::copy_n(rep.table.begin() + ptrdiff_t(rows[i]) * dim, dim, out.begin() + i * dim);
    return out;
  }
  std::vector<float> x(rows.size() * size_t(d.input_dim));
  for (size_t i = 0; i < rows.size(); ++i)
    std::copy_n(d.input(rows[i]), d.input_dim, x.begin() + i * d.input_dim);
  embed(rep, x.data(), int64_t(rows.size()), out.data(), threads);
  return out;
}

EmbeddingPass embed_all(const Representation& rep, const float* X, int64_t n, int threads) {
  if (rep.is_table())
    throw std::logic_error("embed_all: an external representation has no weights to apply");
  constexpr int64_t kChunk = 1024;
  const MlpShape& s = rep.shape;
  const int in = s.in(), d = rep.dim();
  std::vector<int> hidden;  // hidden layers with a ReLU
  for (int l = 0; l + 1 < s.layers(); ++l)
    if (s.relu_after(l)) hidden.push_back(l);
  std::vector<std::vector<char>> alive(hidden.size());
  for (size_t k = 0; k < hidden.size(); ++k) alive[k].assign(s.widths[hidden[k] + 1], 0);
  EmbeddingPass out;
  out.embedding.resize(size_t(n) * d);
  MlpTape<float> tape;
  for (int64_t i0 = 0; i0 < n; i0 += kChunk) {
    const int b = int(std::min(kChunk, n - i0));
    mlp_forward(s, rep.params.data(), X + i0 * in, b, tape, threads);
    std::copy(tape.output(), tape.output() + size_t(b) * d, out.embedding.begin() + i0 * d);
    for (size_t k = 0; k < hidden.size(); ++k) {
      const int w = s.widths[hidden[k] + 1];
      const float* a = tape.act[hidden[k]].data();
      for (int i = 0; i < b; ++i)
        for (int j = 0; j < w; ++j) alive[k][j] |= a[size_t(i) * w + j] > 0.f;
    }
  }
  for (const auto& a : alive) {
    size_t dead = 0;
    for (char c : a) dead += !c;
    out.dead_fraction.push_back(a.empty() ? 0.f : float(dead) / float(a.size()));
  }
  return out;
}

void require_finite(const std::vector<float>& v, const std::string& what) {
  for (size_t i = 0; i < v.size(); ++i)
    if (!std::isfinite(v[i]))
      throw std::runtime_error(what + ": non-finite value " + std::to_string(v[i]) + " at index " +
                               std::to_string(i) + " (training diverged; lower the learning rate)");
}

}  // namespace sirl
