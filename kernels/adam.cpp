#include "kernels/adam.h"

#include <cmath>
#include <limits>

namespace sirl {

double adam_lr(const AdamConfig& cfg, int64_t t) {
  return cfg.lr * std::pow(cfg.decay, double(t - 1));
}

AdamStepScalars adam_begin_step(const AdamConfig& cfg, AdamState& st) {
  return adam_step_scalars(cfg, ++st.step);
}

AdamStepScalars adam_step_scalars(const AdamConfig& cfg, int64_t t) {
  const double lr = adam_lr(cfg, t);
  // torch.optim.Adam (1.13, single-tensor path), float tensors with double scalars cast to float:
  //   m = m·β1 + g·(1−β1);  v = v·β2 + g·g·(1−β2)
  //   denom = sqrt(v) / sqrt(1−β2^t) + ε;  p −= (lr/(1−β1^t)) · m / denom
  const double bc1 = 1.0 - std::pow(cfg.beta1, double(t));
  const double bc2 = 1.0 - std::pow(cfg.beta2, double(t));
  AdamStepScalars s;
  s.step_size = float(lr / bc1);
  s.bc2_sqrt = float(std::sqrt(bc2));
  s.inv_bc2_sqrt = 1.f / s.bc2_sqrt;
  s.b1 = float(cfg.beta1);
  s.b2 = float(cfg.beta2);
  s.eps = float(cfg.eps);
  s.one_minus_b1 = float(1.0 - cfg.beta1);
  s.one_minus_b2 = float(1.0 - cfg.beta2);
  return s;
}

namespace {
inline void adam_update(const AdamStepScalars& s, float* p, const float* g, float* m, float* v,
                        size_t n) {
  const float b1 = s.b1, b2 = s.b2, eps = s.eps, step_size = s.step_size, bc2_sqrt = s.bc2_sqrt,
              inv_bc2_sqrt = s.inv_bc2_sqrt;
  const float one_minus_b1 = s.one_minus_b1, one_minus_b2 = s.one_minus_b2;
  constexpr float kNormal = std::numeric_limits<float>::min();  // 1.18e-38
#pragma omp simd
  for (size_t i = 0; i < n; ++i) {
    float mi = m[i] * b1 + g[i] * one_minus_b1;
    float vi = v[i] * b2 + g[i] * g[i] * one_minus_b2;
    // A moment that underflows is stored as 0 (adam.h: why, and what it changes).
    mi = std::fabs(mi) < kNormal ? 0.f : mi;
    vi = vi < kNormal ? 0.f : vi;
    m[i] = mi;
    v[i] = vi;
    // √v / √(1 − β2^t), the division's bits (adam.h); v ≥ 1.18e-38 or 0, so √v is normal or 0
    const float denom = divide_by_constant(std::sqrt(vi), bc2_sqrt, inv_bc2_sqrt) + eps;
    p[i] -= step_size * (mi / denom);
  }
}
}  // namespace

void adam_apply(const AdamStepScalars& s, float* p, const float* g, float* m, float* v, size_t n) {
  adam_update(s, p, g, m, v, n);
}

void adam_apply_rows(const AdamStepScalars& s, float* p, size_t ld, const float* g, size_t ldg,
                     float* m, float* v, size_t rows, size_t cols) {
  for (size_t r = 0; r < rows; ++r)
    adam_update(s, p + r * ld, g + r * ldg, m + r * ld, v + r * ld, cols);
}

void adam_step(const AdamConfig& cfg, AdamState& st, float* p, const float* g, size_t n) {
  const AdamStepScalars s = adam_begin_step(cfg, st);
  adam_apply(s, p, g, st.m.data(), st.v.data(), n);
}

}  // namespace sirl
