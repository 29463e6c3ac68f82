#include "engine/fpe.h"

#include <cmath>
#include <stdexcept>

#include "kernels/linear_probe.h"

namespace sirl {

namespace {
// Rows `idx` of X [T, w] → [n, w].
std::vector<float> rows(const float* X, int w, const std::vector<int32_t>& idx) {
  std::vector<float> out(idx.size() * size_t(w));
  for (size_t i = 0; i < idx.size(); ++i)
    std::copy(X + size_t(idx[i]) * w, X + size_t(idx[i] + 1) * w, out.begin() + i * w);
  return out;
}
}  // namespace

FpeResult evaluate_fpe(const Representation& rep, const Dataset& d, const FpeSplit& split,
                       int threads) {
  if (split.train.empty() || split.test.empty())
    throw std::invalid_argument("FPE split needs train and test trajectories");
  const int dim = rep.dim(), F = d.feature_count();
  const auto e_tr = embed_rows(rep, d, split.train, threads);
  const auto e_te = embed_rows(rep, d, split.test, threads);
  const auto y_tr = rows(d.features.data(), F, split.train);
  const auto y_te = rows(d.features.data(), F, split.test);
  require_finite(e_tr, "FPE embedding");
  require_finite(e_te, "FPE embedding");
  FpeResult r;
  LinearProbe probe;
  if (rep.method == Method::raw) {
    RidgeProbe ridge =
        fit_ridge_probe_loocv(e_tr.data(), y_tr.data(), int(split.train.size()), dim, F);
    probe = std::move(ridge.probe);
    r.ridge_weight = ridge.weight;
  } else {
    probe = fit_linear_probe(e_tr.data(), y_tr.data(), int(split.train.size()), dim, F);
  }
  r.fpe = linear_probe_mse(probe, e_te.data(), y_te.data(), int(split.test.size()));
  r.train_mse = linear_probe_mse(probe, e_tr.data(), y_tr.data(), int(split.train.size()));
  if (!std::isfinite(r.fpe)) throw std::runtime_error("FPE is not finite");
  return r;
}

}  // namespace sirl
