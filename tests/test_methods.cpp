// The representation methods (SIRL, SIRL+VAE, VAE, Random, the preference baselines) on
// GridRobot at small, fast sizes (fixed seeds).
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "engine/convergence.h"
#include "engine/fpe.h"
#include "engine/methods.h"
#include "engine/train_step.h"
#include "kernels/mlp.h"
#include "kernels/rng.h"
#include "tests/grad_check.h"
#include "tests/grid_world.h"

namespace sirl {
namespace {

using namespace test;

TEST(Methods, SirlFpeBeatsRandomAndVae) {
  const World& w = world();
  const Trained& t = trained();
  const double sirl = evaluate_fpe(t.sirl, w.d, w.bundle.fpe).fpe;
  const double random = evaluate_fpe(t.random, w.d, w.bundle.fpe).fpe;
  const double vae = evaluate_fpe(t.vae_rep, w.d, w.bundle.fpe).fpe;
  RecordProperty("fpe_sirl", std::to_string(sirl));
  RecordProperty("fpe_random", std::to_string(random));
  RecordProperty("fpe_vae", std::to_string(vae));
  EXPECT_LT(sirl, random);
  EXPECT_LT(sirl, vae);
  // Predicting the mean of each normalised feature scores its variance (~0.05–0.1 here); a
  // representation that learned something must do much better.
  EXPECT_LT(sirl, 0.5 * random);
}

TEST(Methods, LossCurvesDecreaseAndAreFinite) {
  const Trained& t = trained();
  for (const auto* c : {&t.sirl.loss_curve, &t.vae.loss_curve}) {
    ASSERT_FALSE(c->empty());
    for (float v : *c) ASSERT_TRUE(std::isfinite(v));
    EXPECT_LT(tail_mean(*c), 0.7 * c->front());
  }
  EXPECT_TRUE(t.random.loss_curve.empty());
}

TEST(Methods, SameSeedSameWeightsWhateverTheThreadCount) {
  const World& w = world();
  Hyper h = fast_hyper();
  h.sirl.epochs = 5;
  const MethodConfig c{Method::sirl, 200, false, h};
  const Representation a = train_representation(w.d, w.bundle, c, 3);
  const Representation b = train_representation(w.d, w.bundle, c, 3, nullptr, {.threads = 2});
  EXPECT_EQ(a.params, b.params);
  EXPECT_EQ(a.loss_curve, b.loss_curve);
  const Representation other = train_representation(w.d, w.bundle, c, 4);
  EXPECT_NE(a.params, other.params);
}

// The multi-threaded paths beside GEMM, SIRL and unfrozen TPA: the VAE's training, the embedding
// pass give bit-identical results on 1 and 2 threads.
TEST(Methods, VaeAndEmbeddingAreTheSameOnTwoThreads) {
  const World& w = world();
  Hyper h = fast_hyper();
  h.vae.epochs = 3;
  const VaeModel v1 = train_vae(w.d, h, 5, {.threads = 1}),
                 v2 = train_vae(w.d, h, 5, {.threads = 2});
  EXPECT_EQ(v1.params, v2.params);
  EXPECT_EQ(v1.loss_curve, v2.loss_curve);
  EXPECT_EQ(v1.kl_per_dim, v2.kl_per_dim);
  std::vector<float> e1(size_t(w.d.count) * 6), e2(e1.size());
  embed(trained().sirl, w.d.inputs.data(), w.d.count, e1.data(), 1);
  embed(trained().sirl, w.d.inputs.data(), w.d.count, e2.data(), 2);
  EXPECT_EQ(e1, e2);  // frozen TPA cells on 2 threads: Tpa.SameResultWhateverTheThreadCount
}

TEST(Methods, RandomIsSirlsStartingPoint) {
  const World& w = world();
  Hyper h = fast_hyper();
  h.sirl.epochs = 0;
  const Representation untrained =
      train_representation(w.d, w.bundle, MethodConfig{Method::sirl, 10, false, h}, 11);
  EXPECT_EQ(untrained.params, trained().random.params);
}

// φ of the VAE method: the encoder's μ columns standardised over Ξ (vae.standardize, default),
// or the raw μ columns without it; checked against the encoder's own forward pass.
TEST(Methods, VaeMeanEncoderIsTheEncodersStandardisedMeanColumns) {
  const World& w = world();
  const Trained& t = trained();
  const int64_t n = w.d.count;
  MlpTape<float> tape;
  mlp_forward(t.vae.shape.encoder, t.vae.params.data(), w.d.inputs.data(), int(n), tape);
  const float* h = tape.output();  // [n, 12]: μ | log σ²
  std::vector<double> mean(6, 0.0), sd(6, 0.0);
  for (int64_t i = 0; i < n; ++i)
    for (int k = 0; k < 6; ++k) mean[k] += h[i * 12 + k] / double(n);
  for (int64_t i = 0; i < n; ++i)
    for (int k = 0; k < 6; ++k) sd[k] += std::pow(h[i * 12 + k] - mean[k], 2) / double(n);
  for (auto& v : sd) v = std::sqrt(v);
  std::vector<float> e(size_t(n) * 6);
  embed(t.vae_rep, w.d.inputs.data(), n, e.data());
  for (int64_t i = 0; i < n; i += 97)
    for (int k = 0; k < 6; ++k)
      EXPECT_NEAR(e[i * 6 + k], (h[i * 12 + k] - mean[k]) / sd[k], 2e-4) << i << " " << k;
  VaeModel raw = t.vae;
  raw.standardize = false;
  const Representation r = vae_mean_encoder(raw);
  embed(r, w.d.inputs.data(), 5, e.data());
  // Equal up to float summation order (the GEMM blocks a 6-wide and a 12-wide output apart).
  for (int i = 0; i < 5; ++i)
    for (int k = 0; k < 6; ++k)
      EXPECT_NEAR(e[i * 6 + k], h[i * 12 + k], 1e-5f * (1 + std::abs(h[i * 12 + k])));
}

TEST(Methods, SirlPlusVaeStartsFromTheEncoder) {
  const World& w = world();
  Hyper h = fast_hyper();
  h.sirl.epochs = 0;
  const Representation r = train_representation(
      w.d, w.bundle, MethodConfig{Method::sirl, 10, true, h}, 11, &trained().vae);
  EXPECT_EQ(r.params, trained().vae_rep.params);
  EXPECT_THROW(train_representation(w.d, w.bundle, MethodConfig{Method::sirl, 10, true, h}, 11),
               std::invalid_argument);  // no VAE given
  EXPECT_THROW(train_representation(w.d, w.bundle, MethodConfig{Method::random, 0, true, h}, 11,
                                    &trained().vae),
               std::invalid_argument);  // not a switch of Random
}

// Methods whose φ(Ξ) is given (an external one, the references truth and raw) are refused by
// training, not handed back as an untrained network under their name.
TEST(Methods, GivenEmbeddingsAreNotTrained) {
  const World& w = world();
  for (Method m : {Method::external, Method::truth, Method::raw}) {
    try {
      train_representation(w.d, w.bundle, MethodConfig{m, 10, false, fast_hyper()}, 11);
      ADD_FAILURE() << method_name(m) << " was trained";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("is not trained"), std::string::npos) << e.what();
    }
  }
}

TEST(Methods, MultiPrefGivesEachHumanNOverKQueries) {
  const World& w = world();
  for (int K : {10, 50}) {
    const PreferenceSet& full = K == 10 ? w.bundle.multipref10 : w.bundle.multipref50;
    for (int64_t N : {100, 250, 500}) {
      const PreferenceSet s = take_per_human(full, N, K);
      ASSERT_EQ(s.count, N);
      std::map<int, int> per;
      for (int h : s.human) ++per[h];
      ASSERT_EQ(int(per.size()), K);
      for (auto [h, n] : per) EXPECT_EQ(n, N / K + (h < N % K ? 1 : 0)) << "K=" << K << " h=" << h;
    }
  }
  EXPECT_THROW(take_per_human(w.bundle.multipref10, 501, 10), std::invalid_argument);
}

// A preference baseline must learn its humans' rewards, not only lower its loss (training on
// flipped labels lowers it as well): SinglePref's head on φ must order fresh pairs of Ξ as its
// human's reward does, and each MultiPref-10 head its human's. Measured 0.860 (SinglePref, 500
// queries) and 0.731 (MultiPref-10, 50 per human, 100 epochs); flipped labels give 1 minus that,
// a head ignoring φ 0.5.
TEST(Methods, PreferenceBaselinesLearnTheirHumansReward) {
  const World& w = world();
  const Hyper h = fast_hyper();
  for (Method m : {Method::singlepref, Method::multipref10}) {
    const Representation r = train_representation(w.d, w.bundle, MethodConfig{m, 500, false, h}, 5);
    ASSERT_EQ(int(r.loss_curve.size()), h.pref.epochs) << method_name(m);
    const RewardSet& humans =
        m == Method::singlepref ? w.bundle.rewards.singlepref : w.bundle.rewards.multipref10;
    ASSERT_EQ(r.heads.size(), size_t(humans.count) * 7) << method_name(m);
    std::vector<float> e(size_t(w.d.count) * 6);
    embed(r, w.d.inputs.data(), w.d.count, e.data());
    Rng rng(77);
    int agree = 0, n = 0;
    for (int q = 0; q < 2000; ++q) {
      const int k = int(rng.uniform_int(uint64_t(humans.count)));
      const int64_t a = int64_t(rng.uniform_int(uint64_t(w.d.count)));
      const int64_t b = int64_t(rng.uniform_int(uint64_t(w.d.count)));
      double ta = 0, tb = 0, pa = r.heads[k * 7 + 6], pb = pa;
      for (int f = 0; f < 4; ++f) {
        ta += humans.weights[k * 4 + f] * w.d.feature(a)[f];
        tb += humans.weights[k * 4 + f] * w.d.feature(b)[f];
      }
      for (int j = 0; j < 6; ++j) {
        pa += r.heads[k * 7 + j] * e[a * 6 + j];
        pb += r.heads[k * 7 + j] * e[b * 6 + j];
      }
      if (std::abs(ta - tb) < 1e-3) continue;  // a tie for the human
      ++n;
      agree += (ta > tb) == (pa > pb);
    }
    RecordProperty(std::string("agreement_") + method_name(m), std::to_string(double(agree) / n));
    EXPECT_GT(double(agree) / n, m == Method::singlepref ? 0.75 : 0.65) << method_name(m);
  }
}

// SIRL trained with N queries uses the first N triplets and no other: changing the triplets
// beyond N changes nothing, changing one within N changes the weights.
TEST(Methods, SirlUsesExactlyItsFirstNTriplets) {
  const World& w = world();
  Hyper h = fast_hyper();
  h.sirl.epochs = 3;
  const MethodConfig c{Method::sirl, 100, false, h};
  const Representation base = train_representation(w.d, w.bundle, c, 2);
  QueryBundle later = w.bundle;
  for (size_t i = 3 * 100; i < later.similarity.idx.size(); ++i)
    later.similarity.idx[i] = int32_t((later.similarity.idx[i] + 1) % w.d.count);
  EXPECT_EQ(train_representation(w.d, later, c, 2).params, base.params);
  QueryBundle within = w.bundle;
  std::swap(within.similarity.idx[3 * 99], within.similarity.idx[3 * 99 + 2]);  // the 100th
  EXPECT_NE(train_representation(w.d, within, c, 2).params, base.params);
}

// SIRL on few triplets fits them all inside the margin; the gradient is then exactly 0, Adam's
// first moments decay to exactly 0, and the exact skip ends training there. The weights and the
// curve must be those of running every epoch, and the skipped epochs' FLOPs are reported.
TEST(Methods, SirlSkipsToTheEndAtAFixedPointWithTheFullRunsBits) {
  const World& w = world();
  Hyper h = fast_hyper();
  h.sirl.epochs = 2500;  // 20 triplets: one step an epoch
  MethodConfig full{Method::sirl, 20, false, h};
  full.skip_fixed_point = false;
  const Representation ref = train_representation(w.d, w.bundle, full, 6);
  ASSERT_EQ(ref.loss_curve.back(), 0.f) << "the setting no longer reaches zero loss";
  MethodConfig skip = full;
  skip.skip_fixed_point = true;
  for (int threads : {1, 2}) {
    const Representation r =
        train_representation(w.d, w.bundle, skip, 6, nullptr, {.threads = threads});
    EXPECT_EQ(r.params, ref.params) << threads << " threads";
    EXPECT_EQ(r.loss_curve, ref.loss_curve) << threads << " threads";
    EXPECT_GT(r.skipped_flops, 0.0);
    // Executed + skipped = every epoch's FLOPs (one batch of 20 triplets an epoch).
    EXPECT_NEAR(r.train_flops + r.skipped_flops, ref.train_flops, 1e-9 * ref.train_flops);
    EXPECT_LT(r.train_flops, ref.train_flops);
  }
  EXPECT_EQ(ref.skipped_flops, 0.0);
  // A training that never reaches its fixed point (too few epochs) runs every epoch.
  skip.hyper.sirl.epochs = 20;
  EXPECT_EQ(train_representation(w.d, w.bundle, skip, 6).skipped_flops, 0.0);
}

// pref.stop = "converged": a preference φ ends at the first epoch from its minimum at which its own
// loss curve has converged, and is then bit for bit the φ (and curve) of a fixed run of that many
// epochs; executed + skipped FLOPs are the full schedule's. The stopping epoch is checked against
// the rule applied by hand to the full run's curve.
TEST(Methods, APreferencePhiStoppedByItsRuleIsTheFixedRunsPhiAtItsStoppingEpoch) {
  const World& w = world();
  Hyper h = fast_hyper();
  h.pref.epochs = 200;
  MethodConfig full{Method::multipref10, 500, false, h};
  const Representation ref = train_representation(w.d, w.bundle, full, 7);
  MethodConfig stop = full;
  stop.hyper.pref_stop = "converged";
  stop.hyper.pref_stop_min_epochs = 20;
  stop.hyper.pref_stop_rel_tol = 0.05;
  // Where the rule says the full run's curve converges first (at or after the minimum).
  int want = h.pref.epochs;
  for (int e = stop.hyper.pref_stop_min_epochs; e < h.pref.epochs; ++e) {
    const std::vector<float> so_far(ref.loss_curve.begin(), ref.loss_curve.begin() + e);
    if (check_convergence(so_far, 0.05).converged) {
      want = e;
      break;
    }
  }
  ASSERT_LT(want, h.pref.epochs) << "the setting no longer converges before its cap";
  const Representation r = train_representation(w.d, w.bundle, stop, 7);
  ASSERT_EQ(int(r.loss_curve.size()), want);
  MethodConfig shorter = full;
  shorter.hyper.pref.epochs = want;
  const Representation cut = train_representation(w.d, w.bundle, shorter, 7);
  EXPECT_EQ(r.params, cut.params);
  EXPECT_EQ(r.heads, cut.heads);
  EXPECT_EQ(r.loss_curve, cut.loss_curve);
  EXPECT_EQ(r.train_flops, cut.train_flops);
  EXPECT_NEAR(r.train_flops + r.skipped_flops, ref.train_flops, 1e-9 * ref.train_flops);
  EXPECT_EQ(ref.skipped_flops, 0.0);
  EXPECT_EQ(cut.skipped_flops, 0.0);
}

// ∂L/∂params of the multi-head step against finite differences of an independent double
// implementation (φ forward + per-human linear heads + Bradley–Terry).
TEST(Methods, MultiheadPreferenceGradientMatchesFiniteDifferences) {
  const int in = 3, d = 2, K = 3, B = 5, T = 8;
  const MlpShape phi{{in, 4, d}};
  Rng rng(9);
  const auto p0 = test::random_vec(phi.param_count() + K * (d + 1), rng, 0.7);
  const auto X = test::random_vec(size_t(T) * in, rng);
  const std::vector<int32_t> pairs = {0, 1, 2, 3, 4, 5, 6, 7, 1, 6};
  const std::vector<int32_t> human = {0, 2, 1, 2, 0};
  const std::vector<double> label = {1, 0, 1, 0.5, 0};
  const double l2 = 0.3;
  // Written out from the definitions, sharing no engine code: φ = Linear-ReLU-Linear on the
  // flat layout (W row-major, then b), r = w_h · φ + c_h for the pair's human h, and the
  // Bradley–Terry loss −[y log σ(r_A − r_B) + (1 − y) log σ(r_B − r_A)] plus l2·(r_A² + r_B²),
  // both averaged over the batch.
  auto loss = [&](const std::vector<double>& p) {
    const int H = 4;
    const double *W1 = p.data(), *b1 = W1 + H * in, *W2 = b1 + H, *b2 = W2 + d * H;
    auto reward = [&](int row, int h) {
      double hid[H], phi_out[d];
      for (int j = 0; j < H; ++j) {
        double z = b1[j];
        for (int k = 0; k < in; ++k) z += W1[j * in + k] * X[size_t(row) * in + k];
        hid[j] = z > 0 ? z : 0;
      }
      for (int j = 0; j < d; ++j) {
        phi_out[j] = b2[j];
        for (int k = 0; k < H; ++k) phi_out[j] += W2[j * H + k] * hid[k];
      }
      const double* w = p.data() + phi.param_count() + h * (d + 1);
      double r = w[d];
      for (int k = 0; k < d; ++k) r += w[k] * phi_out[k];
      return r;
    };
    double total = 0;
    for (int i = 0; i < B; ++i) {
      const double ra = reward(pairs[2 * i], human[i]), rb = reward(pairs[2 * i + 1], human[i]);
      const double pa = 1 / (1 + std::exp(-(ra - rb)));
      total += -(label[i] * std::log(pa) + (1 - label[i]) * std::log(1 - pa));
      total += l2 * (ra * ra + rb * rb);
    }
    return total / B;
  };
  std::vector<float> pf(p0.begin(), p0.end()), Xf(X.begin(), X.end()),
      lf(label.begin(), label.end());
  Trainer t(phi, AdamConfig{1e-9}, pf);
  const float l =
      multihead_preference_train_step(t, 0, adam_step_scalars(t.adam_cfg, 1), K, Xf.data(),
                                      pairs.data(), lf.data(), human.data(), B, float(l2));
  EXPECT_NEAR(l, loss(p0), 1e-5);
  // The step stores no gradient (its Adam update is fused into the backward pass); after Adam's
  // first step the first moment is (1 − β1)·g, element by element.
  std::vector<double> g(t.adam.m.size());
  for (size_t i = 0; i < g.size(); ++i) g[i] = double(t.adam.m[i]) / (1 - t.adam_cfg.beta1);
  test::expect_gradient_matches(loss, p0, g, 2e-3);
}

TEST(Methods, DivergenceIsAClearErrorNamingTheTask) {
  World w = world();
  w.d.inputs[0] = std::nanf("");
  // Make sure row 0 is in the training triplets.
  w.bundle.similarity.idx[0] = 0;
  Hyper h = fast_hyper();
  h.sirl.epochs = 2;
  try {
    train_representation(w.d, w.bundle, MethodConfig{Method::sirl, 100, false, h}, 1);
    FAIL() << "expected a runtime_error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("sirl N=100"), std::string::npos) << e.what();
  }
}

TEST(Methods, NamesRoundTrip) {
  for (auto m : {Method::sirl, Method::vae, Method::multipref10, Method::multipref50,
                 Method::singlepref, Method::random})
    EXPECT_EQ(parse_method(method_name(m)), m);
  EXPECT_THROW(parse_method("sirl+vae"), std::invalid_argument);
}

}  // namespace
}  // namespace sirl
