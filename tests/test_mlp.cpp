#include <gtest/gtest.h>

#include <cmath>

#include "kernels/mlp.h"
#include "probes/cpu_class.h"
#include "tests/grad_check.h"

namespace sirl {
namespace {

// L = Σ c ⊙ MLP(x): checks ∂L/∂params and ∂L/∂x against finite differences.
void check_mlp_gradients(const MlpShape& shape, int batch) {
  Rng rng(42);
  auto params = test::random_vec(shape.param_count(), rng, 0.7);
  auto x = test::random_vec(size_t(batch) * shape.in(), rng);
  auto c = test::random_vec(size_t(batch) * shape.out(), rng);
  auto loss = [&](const std::vector<double>& p, const std::vector<double>& xin) {
    MlpTape<double> tape;
    mlp_forward(shape, p.data(), xin.data(), batch, tape);
    double s = 0;
    for (size_t i = 0; i < c.size(); ++i) s += c[i] * tape.output()[i];
    return s;
  };
  MlpTape<double> tape;
  mlp_forward(shape, params.data(), x.data(), batch, tape);
  std::vector<double> dp(params.size(), 0.0), dx(x.size(), 0.0);
  mlp_backward(shape, params.data(), tape, c.data(), dp.data(), dx.data());
  test::expect_gradient_matches([&](const std::vector<double>& p) { return loss(p, x); }, params,
                                dp);
  test::expect_gradient_matches([&](const std::vector<double>& xi) { return loss(params, xi); }, x,
                                dx);
}

TEST(Mlp, ParamLayoutMatchesPyTorchOrder) {
  MlpShape s{{19, 128, 128, 6}};
  EXPECT_EQ(s.param_count(), size_t(19 * 128 + 128 + 128 * 128 + 128 + 128 * 6 + 6));
  EXPECT_EQ(s.weight_offset(1), size_t(19 * 128 + 128));
  EXPECT_EQ(s.bias_offset(0), size_t(19 * 128));
  EXPECT_DOUBLE_EQ(s.forward_flops(1), 2.0 * (19 * 128 + 128 * 128 + 128 * 6));
}

TEST(Mlp, ForwardMatchesHandComputation) {
  // 2 → 2 → 1: W0 = [[1, −1], [2, 0.5]], b0 = [0, −1]; W1 = [[1, 3]], b1 = [0.25]
  MlpShape s{{2, 2, 1}};
  std::vector<float> p = {1, -1, 2, 0.5f, 0, -1, 1, 3, 0.25f};
  std::vector<float> x = {1, 2, -1, 0};  // two samples
  MlpTape<float> t;
  mlp_forward(s, p.data(), x.data(), 2, t);
  // sample 1: h = relu([−1, 2+1−1]) = [0, 2] → 0 + 6 + 0.25
  // sample 2: h = relu([−1, −2−1]) = [0, 0] → 0.25
  EXPECT_FLOAT_EQ(t.output()[0], 6.25f);
  EXPECT_FLOAT_EQ(t.output()[1], 0.25f);
}

// Each shape flag changes a hand-computed forward value, observed directly.
TEST(Mlp, ReluOnOutputClampsAHandComputedNegativeOutput) {
  // 2 → 2 → 1: W0 = [[1, −1], [2, 0.5]], b0 = [0, −1]; W1 = [[1, −3]], b1 = [0.25]
  // sample x = (1, 2): h = relu([−1, 2]) = [0, 2] → −6 + 0.25 = −5.75; relu → 0.
  MlpShape s{{2, 2, 1}};
  std::vector<float> p = {1, -1, 2, 0.5f, 0, -1, 1, -3, 0.25f};
  std::vector<float> x = {1, 2};
  MlpTape<float> t;
  mlp_forward(s, p.data(), x.data(), 1, t);
  EXPECT_FLOAT_EQ(t.output()[0], -5.75f);
  s.relu_on_output = true;
  mlp_forward(s, p.data(), x.data(), 1, t);
  EXPECT_FLOAT_EQ(t.output()[0], 0.f);
}

TEST(Mlp, Bf16ProductsRoundOperandsByHand) {
  // 1 → 1 linear, W = 1 + 2⁻⁸: halfway between its bf16 neighbours 1 and 1 + 2⁻⁷ (bf16 keeps 7
  // mantissa bits), so round-to-nearest-even makes it 1. x = 3 is exact in bf16. fp32 products
  // give 3 + 3·2⁻⁸ exactly; bf16 products give 3.
  MlpShape s{{1, 1}};
  std::vector<float> p = {1.f + 1.f / 256, 0.f}, x = {3.f};
  MlpTape<float> t;
  mlp_forward(s, p.data(), x.data(), 1, t);
  EXPECT_FLOAT_EQ(t.output()[0], 3.f + 3.f / 256);
  s.bf16_products = true;
  mlp_forward(s, p.data(), x.data(), 1, t);
  EXPECT_FLOAT_EQ(t.output()[0], 3.f);
}

TEST(Mlp, GradientsMatchFiniteDifferences) {
  check_mlp_gradients(MlpShape{{5, 7, 4, 3}}, 4);
}
TEST(Mlp, GradientsWithReluOutput) {
  check_mlp_gradients(MlpShape{{3, 6, 2}, true}, 5);
}
TEST(Mlp, GradientsWithLinearHiddenLayer) {
  // φ (5→7→3, linear output) stacked under a head (3→4→1): layer 1 skips its ReLU.
  check_mlp_gradients(MlpShape{{5, 7, 3, 4, 1}, false, {1}}, 4);
}
TEST(Mlp, LinearHiddenLayerKeepsNegativeValues) {
  // 1 → 1 → 1 with W0 = −1, b0 = 0, W1 = 2, b1 = 0: x = 1 gives h = −1 (no ReLU) → −2.
  MlpShape s{{1, 1, 1}, false, {0}};
  std::vector<float> p = {-1, 0, 2, 0}, x = {1};
  MlpTape<float> t;
  mlp_forward(s, p.data(), x.data(), 1, t);
  EXPECT_FLOAT_EQ(t.output()[0], -2.f);
  s.linear_layers.clear();  // with the ReLU: h = 0 → 0
  mlp_forward(s, p.data(), x.data(), 1, t);
  EXPECT_FLOAT_EQ(t.output()[0], 0.f);
}
TEST(Mlp, SingleLayerGradients) {
  check_mlp_gradients(MlpShape{{4, 3}}, 3);
}

TEST(Mlp, ThreadedGemmIsBitIdentical) {
  MlpShape s{{70, 300, 130, 6}};
  Rng rng(7);
  std::vector<float> p(s.param_count()), x(33 * 70), dout(33 * 6);
  mlp_init(s, p.data(), rng);
  for (auto& v : x) v = float(rng.normal());
  for (auto& v : dout) v = float(rng.normal());
  MlpTape<float> t1, t2;
  std::vector<float> g1(p.size(), 0), g2(p.size(), 0);
  mlp_forward(s, p.data(), x.data(), 33, t1, 1);
  mlp_backward(s, p.data(), t1, dout.data(), g1.data(), nullptr, 1);
  mlp_forward(s, p.data(), x.data(), 33, t2, 2);
  mlp_backward(s, p.data(), t2, dout.data(), g2.data(), nullptr, 2);
  EXPECT_EQ(std::vector<float>(t1.output(), t1.output() + 33 * 6),
            std::vector<float>(t2.output(), t2.output() + 33 * 6));
  EXPECT_EQ(g1, g2);
}

// A training loop reuses one tape step after step: a forward pass into a used tape (its buffers
// hold the last batch's activations) must give what a fresh tape gives, in fp32 and with bf16
// products (the native kernel where the CPU has one: every product here is ≥ 32 wide).
TEST(Mlp, AReusedTapeGivesWhatAFreshOneGives) {
  for (const bool bf16 : {false, true}) {
    MlpShape s{{40, 64, 48, 6}};
    s.bf16_products = bf16;
    Rng rng(13);
    const int batch = 36;
    std::vector<float> p(s.param_count()), x1(batch * 40), x2(batch * 40);
    mlp_init(s, p.data(), rng);
    for (auto& v : x1) v = float(rng.normal());
    for (auto& v : x2) v = float(rng.normal());
    MlpTape<float> used, fresh;
    mlp_forward(s, p.data(), x1.data(), batch, used);
    mlp_forward(s, p.data(), x2.data(), batch, used);
    mlp_forward(s, p.data(), x2.data(), batch, fresh);
    for (int l = 0; l < s.layers(); ++l)
      EXPECT_EQ(used.act[l], fresh.act[l]) << "layer " << l << (bf16 ? ", bf16" : ", fp32");
  }
}

// Three optimizer steps two ways: mlp_backward into a zeroed gradient then adam_step over all
// parameters (the reference, gradient-checked above), and mlp_backward_adam. Weights and both
// moments must agree to the bit, for every thread count.
void expect_fused_backward_adam_matches(const MlpShape& s, int batch) {
  Rng rng(11);
  const size_t P = s.param_count(), O = size_t(batch) * s.out();
  const int steps = 3;
  std::vector<float> p0(P), x(size_t(batch) * s.in()), dout(steps * O);
  mlp_init(s, p0.data(), rng);
  for (auto& v : x) v = float(rng.normal());
  for (auto& v : dout) v = float(rng.normal());
  const AdamConfig cfg{0.01, 0.999};
  std::vector<float> ref = p0;
  AdamState ref_adam(P);
  for (int step = 0; step < steps; ++step) {
    MlpTape<float> t;
    mlp_forward(s, ref.data(), x.data(), batch, t);
    std::vector<float> g(P, 0.f);
    mlp_backward(s, ref.data(), t, dout.data() + step * O, g.data(), static_cast<float*>(nullptr));
    adam_step(cfg, ref_adam, ref.data(), g.data(), P);
  }
  for (int threads : {1, 2}) {
    std::vector<float> p = p0;
    AdamState adam(P);
    for (int step = 0; step < steps; ++step) {
      MlpTape<float> t;
      mlp_forward(s, p.data(), x.data(), batch, t, threads);
      const AdamStepScalars sc = adam_begin_step(cfg, adam);
      mlp_backward_adam(s, p.data(), t, dout.data() + step * O, sc, adam.m.data(), adam.v.data(),
                        threads);
    }
    ASSERT_EQ(adam.step, ref_adam.step);
    ASSERT_NE(p, p0);
    if (avx512_in_use()) {  // the fused pass's row blocks have the whole product's bits
      for (size_t i = 0; i < P; ++i) {
        ASSERT_EQ(p[i], ref[i]) << "weight " << i << ", threads " << threads;
        ASSERT_EQ(adam.m[i], ref_adam.m[i]) << "m " << i;
        ASSERT_EQ(adam.v[i], ref_adam.v[i]) << "v " << i;
      }
      continue;
    }
    // AVX2 paths: a weight gradient by row blocks sums in another order than the whole product
    // (docs/kernels.md), so the two agree to rounding: Adam's moments (linear and quadratic in
    // the gradients) within 1e-4 of their tensor's root mean square, each weight within 1e-5 of
    // its size plus 1e-3 of one step's length lr: m̂/(√v̂ + ε) is ±1 to rounding wherever one
    // gradient dominates, so a rounding change of a gradient moves the step by far less.
    auto rms = [](const std::vector<float>& x) {
      double s2 = 0;
      for (float v : x) s2 += double(v) * v;
      return std::sqrt(s2 / double(x.size()));
    };
    const double m_scale = rms(ref_adam.m), v_scale = rms(ref_adam.v);
    double worst_m = 0, worst_v = 0, worst_p = 0;
    for (size_t i = 0; i < P; ++i) {
      worst_m = std::max(worst_m, std::fabs(double(adam.m[i]) - ref_adam.m[i]) / m_scale);
      worst_v = std::max(worst_v, std::fabs(double(adam.v[i]) - ref_adam.v[i]) / v_scale);
      worst_p = std::max(
          worst_p, std::fabs(double(p[i]) - ref[i]) / (1e-5 * std::fabs(ref[i]) + 1e-3 * cfg.lr));
    }
    EXPECT_LE(worst_m, 1e-4) << "threads " << threads;
    EXPECT_LE(worst_v, 1e-4) << "threads " << threads;
    EXPECT_LE(worst_p, 1.0) << "threads " << threads;
  }
}

TEST(Mlp, FusedBackwardAdamEqualsBackwardThenAdam) {
  expect_fused_backward_adam_matches(MlpShape{{19, 128, 128, 6}}, 64);  // 64-wide slices
  expect_fused_backward_adam_matches(MlpShape{{700, 300, 7}}, 20);      // 256-wide, ragged
  MlpShape unfrozen{{19, 40, 6, 40, 1}};                                // φ + head, linear φ out
  unfrozen.linear_layers = {1};
  expect_fused_backward_adam_matches(unfrozen, 33);
  expect_fused_backward_adam_matches(MlpShape{{3, 5, 2}, true}, 1);  // ReLU output, one row
  expect_fused_backward_adam_matches(MlpShape{{300, 260, 70, 8}},
                                     9);  // on one thread: 256 + 4 units
  MlpShape bf16{{700, 300, 7}};           // bf16 products: the same bits both ways too
  bf16.bf16_products = true;
  expect_fused_backward_adam_matches(bf16, 20);
  MlpShape native{{700, 300, 64}};  // every product ≥ 32 wide: oneDNN's bf16 kernel where native
  native.bf16_products = true;
  expect_fused_backward_adam_matches(native, 48);
  // a native bf16 layer of a shape oneDNN serves in fp32 goes by the same row blocks (256, 256
  // and a ragged 8 emulated) in both passes
  MlpShape native_rows{{600, 520, 6}};
  native_rows.bf16_products = true;
  expect_fused_backward_adam_matches(native_rows, 40);
  // fp32 weight gradients oneDNN serves go by row blocks (600 × 520 with 40 rows: two dimensions
  // ≥ 512), 520 outputs = two blocks of 256 and a ragged one
  expect_fused_backward_adam_matches(MlpShape{{600, 520, 6}}, 40);
  // a big hidden layer with few rows (400 × 700 weights, 20 rows: libxsmm's) also goes by row
  // blocks of 65536 / 700 = 93 (four and a ragged 28), and on one thread its ∂L/∂input block by
  // block as well
  expect_fused_backward_adam_matches(MlpShape{{30, 700, 400, 6}}, 20);
  // and a 700-unit layer (400 → 700, blocks of 163 units), whose whole ∂L/∂input libxsmm sums in
  // another order than block by block: matmul_nn sums over the same blocks, so the bits agree
  expect_fused_backward_adam_matches(MlpShape{{30, 400, 700, 6}}, 20);
}

TEST(Mlp, InitFollowsPyTorchLinearBounds) {
  MlpShape s{{100, 400, 1}};
  std::vector<float> p(s.param_count());
  Rng rng(11);
  mlp_init(s, p.data(), rng);
  const float bound0 = 1.f / 10.f, bound1 = 1.f / 20.f;
  double mean_abs = 0;
  for (size_t i = 0; i < s.bias_offset(0); ++i) {
    ASSERT_LE(std::abs(p[i]), bound0);
    mean_abs += std::abs(p[i]);
  }
  mean_abs /= double(s.bias_offset(0));
  EXPECT_NEAR(mean_abs, bound0 / 2, 0.002);  // |U(−b, b)| has mean b/2
  for (size_t i = s.weight_offset(1); i < p.size(); ++i) ASSERT_LE(std::abs(p[i]), bound1);
  // The first layer's biases too: U(−1/√in, 1/√in) like its weights, not zeros.
  double bias_abs = 0;
  for (size_t i = s.bias_offset(0); i < s.weight_offset(1); ++i) {
    ASSERT_LE(std::abs(p[i]), bound0);
    bias_abs += std::abs(p[i]);
  }
  EXPECT_NEAR(bias_abs / 400, bound0 / 2, 0.01);
  EXPECT_NE(p[s.bias_offset(1)], 0.f);  // the output bias is drawn as well
  // Same seed → same weights; different seed → different.
  std::vector<float> q(p.size()), r(p.size());
  Rng a(11), b(12);
  mlp_init(s, q.data(), a);
  mlp_init(s, r.data(), b);
  EXPECT_EQ(p, q);
  EXPECT_NE(p, r);
}

TEST(Mlp, RejectsBadShapes) {
  EXPECT_THROW(validate(MlpShape{{5}}), std::invalid_argument);
  EXPECT_THROW(validate(MlpShape{{5, 0, 2}}), std::invalid_argument);
  EXPECT_THROW(validate(MlpShape{{5, 3, 2}, false, {1}}), std::invalid_argument);  // output layer
}

}  // namespace
}  // namespace sirl
