// Adam with bf16 moments (kernels/adam_bf16_moments.h) against the fp32 kernel: from moments that
// are bf16 values, a step must move p exactly as adam_apply does on those moments and store the
// fp32 kernel's new moments rounded to the nearest bf16 (rounded here by kernels/bf16.h, an
// independent implementation), step after step, for the flat and the strided kernels.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "kernels/adam.h"
#include "kernels/adam_bf16_moments.h"
#include "kernels/bf16.h"

namespace sirl {
namespace {

std::vector<float> as_floats(const std::vector<uint16_t>& b) {
  std::vector<float> f(b.size());
  for (size_t i = 0; i < b.size(); ++i) {
    const uint32_t u = uint32_t(b[i]) << 16;
    std::memcpy(&f[i], &u, sizeof(float));
  }
  return f;
}

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

// Gradients over many magnitudes: zeros, values whose square underflows, ordinary and large ones.
std::vector<float> gradients(size_t n, std::mt19937& rng) {
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  std::uniform_int_distribution<int> scale(-40, 6);
  std::vector<float> g(n);
  for (size_t i = 0; i < n; ++i)
    g[i] = i % 17 == 0 ? 0.f : u(rng) * std::ldexp(1.f, i % 5 == 0 ? -70 : scale(rng));
  return g;
}

TEST(AdamBf16Moments, EachStepIsTheFp32KernelOnTheStoredMomentsRoundedToBf16) {
  const size_t n = 4099;  // not a multiple of any vector width
  std::mt19937 rng(7);
  AdamConfig cfg;
  cfg.lr = 0.01;
  cfg.decay = 0.999;
  std::vector<float> p(n), p_ref;
  for (auto& x : p) x = std::uniform_real_distribution<float>(-2.f, 2.f)(rng);
  std::vector<uint16_t> m(n, 0), v(n, 0);
  int rounded = 0, flushed = 0;
  for (int64_t t = 1; t <= 40; ++t) {
    const std::vector<float> g = gradients(n, rng);
    const AdamStepScalars s = adam_step_scalars(cfg, t);
    // The reference: the fp32 kernel from the same state (the bf16 moments as floats).
    std::vector<float> m_ref = as_floats(m), v_ref = as_floats(v);
    p_ref = p;
    adam_apply(s, p_ref.data(), g.data(), m_ref.data(), v_ref.data(), n);
    std::vector<uint16_t> m_want(n), v_want(n);
    to_bf16_bits(m_ref.data(), m_want.data(), n);
    to_bf16_bits(v_ref.data(), v_want.data(), n);
    adam_apply_bf16_moments(s, p.data(), g.data(), m.data(), v.data(), n);
    ASSERT_TRUE(same_bits(p, p_ref)) << "step " << t;
    ASSERT_EQ(m, m_want) << "step " << t;
    ASSERT_EQ(v, v_want) << "step " << t;
    for (size_t i = 0; i < n; ++i) {
      rounded += as_floats({m[i]})[0] != m_ref[i];
      flushed += v_ref[i] == 0.f && g[i] != 0.f;  // g² · (1 − β2) below the smallest normal
    }
  }
  EXPECT_GT(rounded, 1000) << "the moments were seldom rounded: a weak test";
  EXPECT_GT(flushed, 0) << "no moment underflowed: the flush to 0 went untested";
}

// The strided kernel updates exactly the block, as the flat kernel row by row, and nothing
// between the rows.
TEST(AdamBf16Moments, TheStridedKernelIsTheFlatKernelRowByRow) {
  const size_t rows = 5, cols = 37, ld = 48, ldg = 40;
  std::mt19937 rng(3);
  std::vector<float> p(rows * ld), g(rows * ldg);
  for (auto& x : p) x = std::uniform_real_distribution<float>(-1.f, 1.f)(rng);
  for (auto& x : g) x = std::uniform_real_distribution<float>(-1.f, 1.f)(rng);
  std::vector<uint16_t> m(rows * ld, 0x3c00), v(rows * ld, 0x3a00);  // 0.0078125, 0.00048828125
  std::vector<float> p2 = p;
  std::vector<uint16_t> m2 = m, v2 = v;
  const AdamStepScalars s = adam_step_scalars(AdamConfig{}, 3);
  adam_apply_rows_bf16_moments(s, p.data(), ld, g.data(), ldg, m.data(), v.data(), rows, cols);
  for (size_t r = 0; r < rows; ++r)
    adam_apply_bf16_moments(s, p2.data() + r * ld, g.data() + r * ldg, m2.data() + r * ld,
                            v2.data() + r * ld, cols);
  EXPECT_TRUE(same_bits(p, p2));
  EXPECT_EQ(m, m2);
  EXPECT_EQ(v, v2);
  for (size_t r = 0; r < rows; ++r)
    for (size_t c = cols; c < ld; ++c) {
      EXPECT_EQ(m[r * ld + c], 0x3c00);  // the padding between rows untouched
      EXPECT_EQ(v[r * ld + c], 0x3a00);
    }
}

}  // namespace
}  // namespace sirl
