#include "kernels/adam.h"

#include <cmath>

namespace sirl {

double adam_lr(const AdamConfig& cfg, int64_t t) {
  return cfg.lr * std::pow(cfg.decay, double(t - 1));
}

void adam_step(const AdamConfig& cfg, AdamState& st, float* p, const float* g, size_t n) {
  const int64_t t = ++st.step;
  const double lr = adam_lr(cfg, t);
  // torch.optim.Adam (1.13, single-tensor path), float tensors with double scalars cast to float:
  //   m = m·β1 + g·(1−β1);  v = v·β2 + g·g·(1−β2)
  //   denom = sqrt(v) / sqrt(1−β2^t) + ε;  p −= (lr/(1−β1^t)) · m / denom
  const double bc1 = 1.0 - std::pow(cfg.beta1, double(t));
  const double bc2 = 1.0 - std::pow(cfg.beta2, double(t));
  const float step_size = float(lr / bc1);
  const float bc2_sqrt = float(std::sqrt(bc2));
  const float b1 = float(cfg.beta1), b2 = float(cfg.beta2), eps = float(cfg.eps);
  const float one_minus_b1 = float(1.0 - cfg.beta1), one_minus_b2 = float(1.0 - cfg.beta2);
  float* m = st.m.data();
  float* v = st.v.data();
#pragma omp simd
  for (size_t i = 0; i < n; ++i) {
    m[i] = m[i] * b1 + g[i] * one_minus_b1;
    v[i] = v[i] * b2 + g[i] * g[i] * one_minus_b2;
    const float denom = std::sqrt(v[i]) / bc2_sqrt + eps;
    p[i] -= step_size * (m[i] / denom);
  }
}

}  // namespace sirl
