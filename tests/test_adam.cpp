#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include "kernels/adam.h"

namespace sirl {
namespace {

// The hand values below are exact real numbers; the kernel runs in float32 as PyTorch does,
// about ten roundings of relative size 6e-8 each, so 1e-6 absolute on O(1) values is ample.
constexpr double kTol = 1e-6;

TEST(Adam, ConstantGradientStepsByTheDecayedLearningRate) {
  // With a constant gradient g, m̂ = g and v̂ = g², so each step moves by lr_t·sign(g)
  // (up to ε): lr 0.1, decay 0.5 → 1 − 0.1 − 0.05 − 0.025 = 0.825.
  AdamConfig cfg;
  cfg.lr = 0.1;
  cfg.decay = 0.5;
  AdamState st(1);
  float p = 1.f, g = 0.5f;
  adam_step(cfg, st, &p, &g, 1);
  EXPECT_NEAR(p, 0.9f, kTol);
  adam_step(cfg, st, &p, &g, 1);
  EXPECT_NEAR(p, 0.85f, kTol);
  adam_step(cfg, st, &p, &g, 1);
  EXPECT_NEAR(p, 0.825f, kTol);
  EXPECT_EQ(st.step, 3);
  EXPECT_DOUBLE_EQ(adam_lr(cfg, 3), 0.025);
}

TEST(Adam, SignFlipHandValues) {
  // lr 1, no decay, g = +1 then −1:
  // t=1: m = 0.1, v = 0.001, m̂ = 1, v̂ = 1 → p = 1 − 1 = 0
  // t=2: m = 0.09 − 0.1 = −0.01, v = 0.000999 + 0.001 = 0.001999,
  //      m̂ = −0.01/0.19, v̂ = 0.001999/0.001999 = 1 → p = 0 + 0.01/0.19 = 0.0526316
  AdamConfig cfg;
  cfg.lr = 1.0;
  AdamState st(1);
  float p = 1.f, g = 1.f;
  adam_step(cfg, st, &p, &g, 1);
  EXPECT_NEAR(p, 0.f, kTol);
  g = -1.f;
  adam_step(cfg, st, &p, &g, 1);
  EXPECT_NEAR(p, 0.01 / 0.19, kTol);
  EXPECT_NEAR(st.m[0], -0.01f, 1e-7);
  EXPECT_NEAR(st.v[0], 0.001999, 1e-9);
}

TEST(Adam, ZeroGradientLeavesFreshParametersAlone) {
  AdamConfig cfg;
  AdamState st(3);
  std::vector<float> p = {1, 2, 3}, g = {0, 0, 0};
  adam_step(cfg, st, p.data(), g.data(), 3);
  EXPECT_EQ(p, (std::vector<float>{1, 2, 3}));
}

// A moment that falls below the smallest normal float is stored as 0 (adam.h). Hand values:
// m = 1.5e-38 and g = 0 decay by β1 = 0.9 to 1.35e-38 and 1.215e-38 (both normal, kept), then
// 1.0935e-38 < 1.1755e-38: stored as 0. v = 1.2e-38 decays by β2 = 0.999 to 1.1988e-38 (kept),
// then 1.1976e-38 (kept) ... and is 0 from the step where it would go below 1.1755e-38.
TEST(Adam, MomentsThatUnderflowAreStoredAsZero) {
  AdamConfig cfg;
  AdamState st(1);
  st.m[0] = 1.5e-38f;
  st.v[0] = 1.2e-38f;
  float p = 0.5f, g = 0.f;
  adam_step(cfg, st, &p, &g, 1);
  EXPECT_FLOAT_EQ(st.m[0], 1.35e-38f);
  adam_step(cfg, st, &p, &g, 1);
  EXPECT_FLOAT_EQ(st.m[0], 1.215e-38f);
  adam_step(cfg, st, &p, &g, 1);
  EXPECT_EQ(st.m[0], 0.f);
  EXPECT_GT(st.v[0], 1.19e-38f);  // 1.2e-38 · 0.999³ = 1.1964e-38: still normal
  // v reaches the bound after ln(1.1755/1.2)/ln(0.999) ≈ 20.6 steps in all
  for (int t = 3; t < 20; ++t) adam_step(cfg, st, &p, &g, 1);
  EXPECT_GT(st.v[0], 0.f);
  adam_step(cfg, st, &p, &g, 1);
  EXPECT_EQ(st.v[0], 0.f);
  EXPECT_EQ(p, 0.5f);
}

// What the flush leaves alone: with moments kept subnormal (PyTorch's arithmetic, written out
// here in float), 2000 steps of a zero gradient after 10 of a real one move every parameter of
// ordinary size to the same bits, and no stored moment is ever subnormal.
TEST(Adam, FlushingUnderflowedMomentsKeepsTheParametersBits) {
  AdamConfig cfg;
  cfg.lr = 1e-3;
  const std::vector<float> p0 = {0.5f, -0.03f, 2e-6f, -1.0f};
  std::vector<float> p = p0, ref = p0, rm(4, 0.f), rv(4, 0.f);
  AdamState st(4);
  bool reference_went_subnormal = false;
  for (int t = 1; t <= 2010; ++t) {
    std::vector<float> g(4, 0.f);
    if (t <= 10) g = {0.3f, -1e-3f, 5e-5f, 1.f};
    adam_step(cfg, st, p.data(), g.data(), 4);
    const double bc1 = 1.0 - std::pow(0.9, t), bc2 = 1.0 - std::pow(0.999, t);
    const float step_size = float(cfg.lr / bc1), bc2_sqrt = float(std::sqrt(bc2));
    for (int i = 0; i < 4; ++i) {
      rm[i] = rm[i] * 0.9f + g[i] * float(1.0 - 0.9);
      rv[i] = rv[i] * 0.999f + g[i] * g[i] * float(1.0 - 0.999);
      ref[i] -= step_size * (rm[i] / (std::sqrt(rv[i]) / bc2_sqrt + 1e-8f));
      reference_went_subnormal |= std::fpclassify(rm[i]) == FP_SUBNORMAL;
      ASSERT_NE(std::fpclassify(st.m[i]), FP_SUBNORMAL) << "step " << t;
      ASSERT_NE(std::fpclassify(st.v[i]), FP_SUBNORMAL) << "step " << t;
    }
  }
  EXPECT_EQ(std::memcmp(p.data(), ref.data(), sizeof(float) * 4), 0);
  EXPECT_NE(p, p0);                                          // the real steps moved them
  for (int i = 0; i < 4; ++i) EXPECT_EQ(st.m[i], 0.f) << i;  // 0.9^2000: flushed
  EXPECT_TRUE(reference_went_subnormal);  // the run crossed the range the flush changes
}

// adam_apply_rows on a 3 × 4 block of a 5 × 7 matrix (row stride 7, gradient stride 4): each of
// the block's elements gets exactly adam_apply's update, and nothing outside the block changes.
TEST(Adam, RowsOfABlockGetTheSameUpdateAndNothingElseMoves) {
  const size_t R = 5, C = 7, rows = 3, cols = 4, r0 = 1, c0 = 2;
  std::vector<float> p(R * C), m(R * C), v(R * C), g(rows * cols);
  for (size_t i = 0; i < p.size(); ++i) {
    p[i] = 0.1f * float(i) - 1.f;
    m[i] = 0.01f * float(i % 5);
    v[i] = 0.001f * float(i % 3);
  }
  for (size_t i = 0; i < g.size(); ++i) g[i] = 0.3f * float(i) - 1.45f;  // none 0
  AdamConfig cfg;
  AdamState st(0);
  st.step = 4;
  const AdamStepScalars sc = adam_begin_step(cfg, st);
  std::vector<float> p2 = p, m2 = m, v2 = v;
  const size_t at = r0 * C + c0;
  adam_apply_rows(sc, p2.data() + at, C, g.data(), cols, m2.data() + at, v2.data() + at, rows,
                  cols);
  std::vector<float> p1 = p, m1 = m, v1 = v;
  for (size_t r = 0; r < rows; ++r)
    for (size_t c = 0; c < cols; ++c) {
      const size_t i = (r0 + r) * C + c0 + c;
      adam_apply(sc, &p1[i], &g[r * cols + c], &m1[i], &v1[i], 1);
    }
  EXPECT_EQ(p2, p1);
  EXPECT_EQ(m2, m1);
  EXPECT_EQ(v2, v1);
  size_t moved = 0;
  for (size_t i = 0; i < p.size(); ++i) moved += p2[i] != p[i];
  EXPECT_EQ(moved, rows * cols);  // every element of the block (no gradient here is 0)
}

// Adam divides √v by step t's √(1 − β2^t) as a multiplication by its reciprocal and one FMA
// correction (adam.h, divide_by_constant): the division's bits for every float significand, at
// several exponents, for the divisors of steps from the first (√0.001) to where they reach 1.
TEST(Adam, DividingByTheStepsConstantGivesTheDivisionsBits) {
  const AdamConfig cfg;
  size_t checked = 0;
  for (int64_t t : {1, 2, 3, 7, 50, 333, 1000, 4000, 20000, 1000000}) {
    const AdamStepScalars s = adam_step_scalars(cfg, t);
    ASSERT_EQ(s.inv_bc2_sqrt, 1.f / s.bc2_sqrt);
    for (uint32_t mantissa = 0; mantissa < (1u << 23); ++mantissa) {
      const float x = std::bit_cast<float>(0x3f800000u | mantissa);  // [1, 2)
      const float q = divide_by_constant(x, s.bc2_sqrt, s.inv_bc2_sqrt);
      if (q != x / s.bc2_sqrt) FAIL() << "t " << t << ": " << x << " / " << s.bc2_sqrt;
      if (mantissa % 61 == 0)  // √v spans 1e-19 (v at the flush) to 1e19
        for (float scale : {0x1p-63f, 0x1p-20f, 0x1p20f, 0x1p63f})
          if (divide_by_constant(x * scale, s.bc2_sqrt, s.inv_bc2_sqrt) != x * scale / s.bc2_sqrt)
            FAIL() << "t " << t << ": " << x * scale << " / " << s.bc2_sqrt;
      ++checked;
    }
    EXPECT_EQ(divide_by_constant(0.f, s.bc2_sqrt, s.inv_bc2_sqrt), 0.f);
  }
  EXPECT_EQ(checked, size_t(10) << 23);
}

// The same for every divisor Adam can use: the float √(1 − β2^t) (β2 = 0.999) takes 10 030
// distinct values, and from step 16 628 on it is 1. About 15 s in a release build, so not run by
// default: sirl_tests --gtest_also_run_disabled_tests --gtest_filter='Adam.DISABLED_*'
TEST(Adam, DISABLED_DividingByEveryStepsConstantGivesTheDivisionsBits) {
  const AdamConfig cfg;
  float last = 0;
  int64_t t = 1, divisors = 0;
  for (; last != 1.f; ++t) {
    const AdamStepScalars s = adam_step_scalars(cfg, t);
    if (s.bc2_sqrt == last) continue;
    last = s.bc2_sqrt;
    ++divisors;
    uint32_t bad = 0;
    for (uint32_t mantissa = 0; mantissa < (1u << 23); ++mantissa) {
      const float x = std::bit_cast<float>(0x3f800000u | mantissa);
      bad += divide_by_constant(x, s.bc2_sqrt, s.inv_bc2_sqrt) != x / s.bc2_sqrt;
    }
    ASSERT_EQ(bad, 0u) << "t " << t << ", divisor " << s.bc2_sqrt;
  }
  EXPECT_GT(divisors, 10000);  // the loop went through them all, up to 1
}

}  // namespace
}  // namespace sirl
