// The VAE kernel: ELBO gradients against finite differences, the KL's closed form and clamp.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "kernels/rng.h"
#include "kernels/vae.h"
#include "tests/grad_check.h"

namespace sirl {
namespace {

TEST(Vae, GradientMatchesFiniteDifferencesInBothElboForms) {
  const VaeShape s = make_vae_shape(5, {8, 7}, 3);
  EXPECT_EQ(s.encoder.widths, (std::vector<int>{5, 8, 7, 6}));
  EXPECT_EQ(s.decoder.widths, (std::vector<int>{3, 7, 8, 5}));
  Rng rng(21);
  const int B = 4;
  auto params = test::random_vec(s.param_count(), rng, 0.4);
  auto x = test::random_vec(B * 5, rng);
  auto eps = test::random_vec(B * 3, rng);
  for (VaeElbo form : {VaeElbo::sum_over_inputs, VaeElbo::mean_over_inputs}) {
    VaeWorkspace<double> ws;
    std::vector<double> g(params.size(), 0.0);
    VaeLossParts parts;
    const double L = vae_loss_and_grad(s, params.data(), x.data(), B, eps.data(), 0.3, form,
                                       g.data(), ws, &parts);
    EXPECT_NEAR(L, parts.reconstruction + 0.3 * parts.kl, 1e-12);
    // The two forms differ by the input width exactly: sum = in · mean.
    EXPECT_NEAR(parts.reconstruction,
                (form == VaeElbo::sum_over_inputs ? 5.0 : 1.0) * parts.squared_error, 1e-12);
    EXPECT_GE(parts.kl, 0.0);
    double kl_sum = 0;
    for (double k : parts.kl_per_dim) kl_sum += k;
    EXPECT_NEAR(kl_sum, parts.kl, 1e-12);
    test::expect_gradient_matches(
        [&](const std::vector<double>& p) {
          VaeWorkspace<double> w;
          return vae_loss_and_grad(s, p.data(), x.data(), B, eps.data(), 0.3, form,
                                   static_cast<double*>(nullptr), w);
        },
        params, g);
  }
}

TEST(Vae, KlIsZeroForStandardNormalPosterior) {
  // Encoder with all-zero weights and biases outputs μ = 0, log σ² = 0: KL(N(0,1) ‖ N(0,1)) = 0.
  const VaeShape s = make_vae_shape(4, {5}, 2);
  std::vector<double> p(s.param_count(), 0.0), x(2 * 4, 1.0), eps(2 * 2, 0.5);
  VaeWorkspace<double> ws;
  VaeLossParts parts;
  vae_loss_and_grad(s, p.data(), x.data(), 2, eps.data(), 1.0, VaeElbo::mean_over_inputs,
                    static_cast<double*>(nullptr), ws, &parts);
  EXPECT_DOUBLE_EQ(parts.kl, 0.0);
  EXPECT_DOUBLE_EQ(parts.reconstruction, 1.0);  // decoder outputs 0, targets 1: mean of 1s
  vae_loss_and_grad(s, p.data(), x.data(), 2, eps.data(), 1.0, VaeElbo::sum_over_inputs,
                    static_cast<double*>(nullptr), ws, &parts);
  EXPECT_DOUBLE_EQ(parts.reconstruction, 4.0);  // summed over the 4 inputs, mean over the batch
}

TEST(Vae, ALogVarianceBelowTheClampIsPulledBackByTheKl) {
  // Zero weights, the log σ² bias at −40 (below the clamp at −30): the sample path has no
  // gradient there, the KL's passes straight through: ∂L/∂b_lv = λ·½·(e^−30 − 1) summed over
  // the batch and divided by it, i.e. λ·½·(e^−30 − 1) < 0, so gradient descent raises log σ².
  const VaeShape s = make_vae_shape(3, {4}, 1);
  std::vector<double> p(s.param_count(), 0.0), x(2 * 3, 0.3), eps(2, 0.7);
  const size_t b_lv = s.encoder.bias_offset(s.encoder.layers() - 1) + 1;  // [μ, log σ²]
  p[b_lv] = -40;
  std::vector<double> g(p.size(), 0.0);
  VaeWorkspace<double> ws;
  vae_loss_and_grad(s, p.data(), x.data(), 2, eps.data(), 0.01, VaeElbo::sum_over_inputs, g.data(),
                    ws);
  EXPECT_NEAR(g[b_lv], 0.01 * 0.5 * (std::exp(-30.0) - 1), 1e-15);
  EXPECT_LT(g[b_lv], 0.0);
}

TEST(Vae, KlPerDimensionMatchesTheClosedForm) {
  // Zero weights: every row's μ_k and log σ²_k are the last encoder layer's biases, so
  // KL_k = −½ (1 + lv_k − μ_k² − exp(lv_k)) for every row, computed here by hand.
  const VaeShape s = make_vae_shape(3, {4}, 2);
  std::vector<double> p(s.param_count(), 0.0), x(3 * 3, 0.2), eps(3 * 2, 0.1);
  const int last = s.encoder.layers() - 1;
  double* b = p.data() + s.encoder.bias_offset(last);  // [μ_0, μ_1, lv_0, lv_1]
  b[0] = 1.0, b[1] = -0.5, b[2] = std::log(0.25), b[3] = 0.0;
  VaeWorkspace<double> ws;
  VaeLossParts parts;
  vae_loss_and_grad(s, p.data(), x.data(), 3, eps.data(), 0.01, VaeElbo::sum_over_inputs,
                    static_cast<double*>(nullptr), ws, &parts);
  ASSERT_EQ(parts.kl_per_dim.size(), 2u);
  EXPECT_NEAR(parts.kl_per_dim[0], -0.5 * (1 + std::log(0.25) - 1.0 - 0.25), 1e-12);
  EXPECT_NEAR(parts.kl_per_dim[1], -0.5 * (1 + 0.0 - 0.25 - 1.0), 1e-12);
  EXPECT_NEAR(parts.kl, parts.kl_per_dim[0] + parts.kl_per_dim[1], 1e-12);
}

// Three steps two ways: vae_loss_and_grad into a zeroed gradient then adam_step (the reference;
// its gradient is checked above), and vae_loss_and_adam_step. Weights, moments and losses agree
// to the bit for 1 and 2 threads, in fp32 and with bf16 products. The 300-wide input and
// 260-wide layers cut the products into several column slices.
TEST(Vae, FusedAdamStepEqualsGradientThenAdam) {
  for (bool bf16 : {false, true}) {
    VaeShape s = make_vae_shape(300, {260, 70}, 4);
    s.encoder.bf16_products = s.decoder.bf16_products = bf16;
    const size_t P = s.param_count();
    const int B = 9, steps = 3;
    Rng rng(21);
    std::vector<float> p0(P), x(size_t(B) * 300), eps(size_t(steps) * B * 4);
    mlp_init(s.encoder, p0.data(), rng);
    mlp_init(s.decoder, p0.data() + s.encoder.param_count(), rng);
    for (auto& e : x) e = float(rng.normal());
    for (auto& e : eps) e = float(rng.normal());
    const AdamConfig cfg{0.003, 0.999};
    std::vector<float> ref = p0, ref_loss;
    AdamState ref_adam(P);
    VaeWorkspace<float> ws;
    for (int k = 0; k < steps; ++k) {
      std::vector<float> g(P, 0.f);
      ref_loss.push_back(vae_loss_and_grad(s, ref.data(), x.data(), B, eps.data() + k * B * 4, 0.5f,
                                           VaeElbo::sum_over_inputs, g.data(), ws));
      adam_step(cfg, ref_adam, ref.data(), g.data(), P);
    }
    for (int threads : {1, 2}) {
      std::vector<float> p = p0;
      AdamState adam(P);
      VaeWorkspace<float> w;
      for (int k = 0; k < steps; ++k) {
        const AdamStepScalars sc = adam_begin_step(cfg, adam);
        const float loss = vae_loss_and_adam_step(s, p.data(), x.data(), B, eps.data() + k * B * 4,
                                                  0.5f, VaeElbo::sum_over_inputs, sc, adam.m.data(),
                                                  adam.v.data(), w, nullptr, threads);
        EXPECT_EQ(loss, ref_loss[k]) << "step " << k << ", threads " << threads;
      }
      EXPECT_EQ(p, ref) << "bf16 " << bf16 << ", threads " << threads;
      EXPECT_EQ(adam.m, ref_adam.m);
      EXPECT_EQ(adam.v, ref_adam.v);
      EXPECT_NE(p, p0);
    }
  }
}

}  // namespace
}  // namespace sirl
