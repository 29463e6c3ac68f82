#include <gtest/gtest.h>

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

}  // namespace
}  // namespace sirl
