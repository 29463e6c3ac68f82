#include "engine/train_step.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>

#include "kernels/bradley_terry_loss.h"
#include "kernels/triplet_loss.h"

namespace sirl {

Trainer::Trainer(MlpShape s, AdamConfig cfg, std::vector<float> initial, int m)
    : shape(std::move(s)),
      models(m),
      adam_cfg(cfg),
      params(std::move(initial)),
      adam(params.size()),
      work(size_t(std::max(m, 0))),
      losses(size_t(std::max(m, 0)), 0.f) {
  validate(shape);
  if (models < 1 || params.size() % size_t(models) != 0)
    throw std::invalid_argument("Trainer: parameters are not models × a model's");
  stride = params.size() / size_t(models);
  if (stride < shape.param_count())
    throw std::invalid_argument("Trainer: fewer parameters per model than the network has");
}

void gather_by_role(const float* X, int in, const int32_t* idx, int B, int roles, float* out) {
  for (int role = 0; role < roles; ++role)
    for (int i = 0; i < B; ++i)
      std::memcpy(out + (size_t(role) * B + i) * in, X + size_t(idx[size_t(i) * roles + role]) * in,
                  sizeof(float) * in);
}

namespace {

// Model m's gather [roles·B, in] and forward pass; returns its output [roles·B, out].
const float* forward_of_model(Trainer& t, int m, const float* X, const int32_t* idx, int B,
                              int roles, int threads) {
  const int in = t.shape.in(), rows = roles * B;
  Trainer::ModelWork& w = t.work[m];
  w.x.resize(size_t(rows) * in);
  w.d_out.resize(size_t(rows) * t.shape.out());
  gather_by_role(X, in, idx, B, roles, w.x.data());
  mlp_forward(t.shape, t.model_params(m), w.x.data(), rows, w.tape, threads);
  return w.tape.output();
}

// Model m's backward pass from its d_out fused with Adam (mlp_backward_adam).
void backward_of_model(Trainer& t, int m, const AdamStepScalars& step, int threads) {
  const size_t off = size_t(m) * t.stride;
  mlp_backward_adam(t.shape, t.params.data() + off, t.work[m].tape, t.work[m].d_out.data(), step,
                    t.adam.m.data() + off, t.adam.v.data() + off, threads);
}

// The model's trailing parameters, when its step does not use them: their zero gradient's update.
void update_unused_trailing(Trainer& t, int m, const AdamStepScalars& step) {
  const size_t P = t.shape.param_count(), rest = t.stride - P, off = size_t(m) * t.stride + P;
  if (rest == 0) return;
  const std::vector<float> zero(rest, 0.f);
  adam_apply(step, t.params.data() + off, zero.data(), t.adam.m.data() + off, t.adam.v.data() + off,
             rest);
}

// A one-network step: forward, loss(out, d_out) (returns the loss, writes ∂L/∂output), backward.
template <typename Loss>
float step_of_model(Trainer& t, int m, const AdamStepScalars& step, const float* X,
                    const int32_t* idx, int B, int roles, int threads, Loss&& loss) {
  const float* out = forward_of_model(t, m, X, idx, B, roles, threads);
  t.losses[m] = loss(out, t.work[m].d_out.data());
  backward_of_model(t, m, step, threads);
  update_unused_trailing(t, m, step);
  return t.losses[m];
}

}  // namespace

float triplet_train_step(Trainer& t, int m, const AdamStepScalars& step, const float* X,
                         const int32_t* triplets, int B, float margin, int threads) {
  const int d = t.shape.out();
  return step_of_model(t, m, step, X, triplets, B, 3, threads, [&](const float* emb, float* demb) {
    return symmetric_triplet_loss(emb, B, d, margin, demb);
  });
}

float preference_train_step(Trainer& t, int m, const AdamStepScalars& step, const float* X,
                            const int32_t* pairs, const float* label, int B, float l2_weight,
                            int threads) {
  return step_of_model(t, m, step, X, pairs, B, 2, threads, [&](const float* r, float* dr) {
    return bradley_terry_loss(r, label, B, l2_weight, dr);
  });
}

float multihead_preference_train_step(Trainer& t, int m, const AdamStepScalars& step, int K,
                                      const float* X, const int32_t* pairs, const float* label,
                                      const int32_t* human, int B, float l2_weight, int threads) {
  const int d = t.shape.out();
  const size_t P = t.shape.param_count();
  if (t.stride != P + size_t(K) * (d + 1))
    throw std::invalid_argument("multihead_preference_train_step: a model is not φ and K heads");
  float* heads = t.model_params(m) + P;                                // [K, d + 1]
  const float* emb = forward_of_model(t, m, X, pairs, B, 2, threads);  // [2B, d]: A rows, B rows
  // r [2B]: each row scored by its pair's head.
  std::vector<float> r(size_t(2) * B), dr(size_t(2) * B);
  for (int j = 0; j < 2 * B; ++j) {
    const float* w = heads + size_t(human[j % B]) * (d + 1);
    float s = w[d];
    for (int k = 0; k < d; ++k) s += w[k] * emb[size_t(j) * d + k];
    r[j] = s;
  }
  t.losses[m] = bradley_terry_loss(r.data(), label, B, l2_weight, dr.data());
  // The heads' gradient, rows in order, and ∂L/∂φ from the heads before their update.
  std::vector<float> dheads(size_t(K) * (d + 1), 0.f);  // [K, d + 1]
  float* d_out = t.work[m].d_out.data();
  for (int j = 0; j < 2 * B; ++j) {
    const int h = human[j % B];
    const float* w = heads + size_t(h) * (d + 1);
    float* dw = dheads.data() + size_t(h) * (d + 1);
    for (int k = 0; k < d; ++k) {
      d_out[size_t(j) * d + k] = dr[j] * w[k];  // ∂L/∂φ = dr · w
      dw[k] += dr[j] * emb[size_t(j) * d + k];  // ∂L/∂w = dr · φ
    }
    dw[d] += dr[j];
  }
  // One Adam step over [φ | heads]: φ's in its fused backward pass (the same bits as a stored
  // gradient and adam_step, without writing, zeroing and re-reading a gradient of φ's size).
  backward_of_model(t, m, step, threads);
  const size_t off = size_t(m) * t.stride + P;
  adam_apply(step, heads, dheads.data(), t.adam.m.data() + off, t.adam.v.data() + off,
             dheads.size());
  return t.losses[m];
}

double epoch_train_flops(const MlpShape& s, int64_t n, int batch, int roles, int copies,
                         double total) {
  for (int64_t i0 = 0; i0 < n; i0 += batch)
    total += copies * s.train_flops(roles * int(std::min<int64_t>(batch, n - i0)));
  return total;
}

}  // namespace sirl
