#include "kernels/adam_bf16_moments.h"

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

namespace sirl {

namespace {

// One loop over the parameters: the moments widened from bf16 (exact), adam_apply's arithmetic
// (kernels/adam.cpp, the same expressions in the same order), the new moments rounded to the
// nearest bf16, ties to even. (Moments are finite: no NaN handling; a value rounding past bf16's
// largest would become inf, as IEEE rounding does.)
void update(const AdamStepScalars& s, float* p, const float* g, uint16_t* m, uint16_t* v,
            size_t n) {
  const float b1 = s.b1, b2 = s.b2, eps = s.eps, step_size = s.step_size, bc2_sqrt = s.bc2_sqrt,
              inv_bc2_sqrt = s.inv_bc2_sqrt;
  const float one_minus_b1 = s.one_minus_b1, one_minus_b2 = s.one_minus_b2;
  constexpr float kNormal = std::numeric_limits<float>::min();
#pragma omp simd
  for (size_t i = 0; i < n; ++i) {
    const float m0 = std::bit_cast<float>(uint32_t(m[i]) << 16);
    const float v0 = std::bit_cast<float>(uint32_t(v[i]) << 16);
    float mi = m0 * b1 + g[i] * one_minus_b1;
    float vi = v0 * b2 + g[i] * g[i] * one_minus_b2;
    mi = std::fabs(mi) < kNormal ? 0.f : mi;  // as adam_apply (kernels/adam.h: why)
    vi = vi < kNormal ? 0.f : vi;
    const uint32_t mu = std::bit_cast<uint32_t>(mi), vu = std::bit_cast<uint32_t>(vi);
    m[i] = uint16_t((mu + 0x7fffu + ((mu >> 16) & 1u)) >> 16);
    v[i] = uint16_t((vu + 0x7fffu + ((vu >> 16) & 1u)) >> 16);
    const float denom = divide_by_constant(std::sqrt(vi), bc2_sqrt, inv_bc2_sqrt) + eps;
    p[i] -= step_size * (mi / denom);
  }
}

}  // namespace

void adam_apply_bf16_moments(const AdamStepScalars& s, float* p, const float* g, uint16_t* m,
                             uint16_t* v, size_t n) {
  update(s, p, g, m, v, n);
}

void adam_apply_rows_bf16_moments(const AdamStepScalars& s, float* p, size_t ld, const float* g,
                                  size_t ldg, uint16_t* m, uint16_t* v, size_t rows, size_t cols) {
  for (size_t r = 0; r < rows; ++r)
    update(s, p + r * ld, g + r * ldg, m + r * ld, v + r * ld, cols);
}

}  // namespace sirl
