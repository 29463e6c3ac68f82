#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "engine/for_each_model.h"
#include "engine/train_step.h"
#include "kernels/bradley_terry_loss.h"
#include "kernels/rng.h"
#include "kernels/triplet_loss.h"

namespace sirl {
namespace {

// A model's step the plain way, as a reference: gather its rows, forward pass, loss, the whole
// gradient into a zeroed buffer (mlp_backward), then one Adam step over it (adam_step, counting
// its own step number). loss(out, d_out) returns the loss and writes ∂L/∂output.
struct PlainModel {
  std::vector<float> params, grad;
  AdamState adam;
  MlpTape<float> tape;
  template <typename Loss>
  float step(const MlpShape& s, const AdamConfig& cfg, const float* X, const int32_t* idx, int B,
             int roles, Loss&& loss) {
    const int rows = roles * B;
    std::vector<float> x(size_t(rows) * s.in()), d_out(size_t(rows) * s.out());
    gather_by_role(X, s.in(), idx, B, roles, x.data());
    mlp_forward(s, params.data(), x.data(), rows, tape);
    const float l = loss(tape.output(), d_out.data());
    grad.assign(params.size(), 0.f);
    mlp_backward(s, params.data(), tape, d_out.data(), grad.data(), nullptr);
    adam_step(cfg, adam, params.data(), grad.data(), params.size());
    return l;
  }
};

// A Trainer of M models (a TPA cell's heads, an ensemble of φ) against each model trained alone
// the plain way on its own rows: the parameters and both Adam moments must agree to the bit, and
// each model's loss too. The Trainer's models take their steps three ways: all models' step k
// before any model's k + 1 (over 1 and 2 threads), model after model in reverse, each its steps in
// a row (as the epoch loop's stretches do), and each model's products on 2 threads. Three steps
// with a decaying rate, so the moments carry over and a wrong step number shows.
// step(t, m, scalars, X, rows, labels, B, threads) is the Trainer's step;
// loss(out, labels, B, d_out) the same objective for the plain reference.
template <typename Step, typename Loss>
void expect_each_model_equals_it_trained_plainly(const MlpShape& s, int roles, Step&& step,
                                                 Loss&& loss) {
  const int M = 3, B = 7, T = 40, steps = 3;
  const size_t P = s.param_count();
  Rng rng(21);
  std::vector<float> X(size_t(T) * s.in()), p0(M * P);
  for (auto& v : X) v = float(rng.normal());
  for (int m = 0; m < M; ++m) mlp_init(s, p0.data() + m * P, rng);
  std::vector<int32_t> idx(size_t(steps) * M * B * roles);
  std::vector<float> label(size_t(steps) * M * B);
  for (auto& v : idx) v = int32_t(rng.uniform_int(T));
  for (auto& v : label) v = float(rng.uniform_int(2));
  const AdamConfig cfg{0.01, 0.99};
  auto rows_of = [&](int k, int m) { return idx.data() + (size_t(k) * M + m) * B * roles; };
  auto labels_of = [&](int k, int m) { return label.data() + (size_t(k) * M + m) * B; };

  std::vector<PlainModel> plain(M);
  std::vector<std::vector<float>> loss_plain(M);
  for (int m = 0; m < M; ++m) {
    plain[m].params.assign(p0.begin() + m * P, p0.begin() + (m + 1) * P);
    plain[m].adam = AdamState(P);
    for (int k = 0; k < steps; ++k)
      loss_plain[m].push_back(plain[m].step(
          s, cfg, X.data(), rows_of(k, m), B, roles,
          [&](const float* out, float* d_out) { return loss(out, labels_of(k, m), B, d_out); }));
  }
  auto expect_equal = [&](const Trainer& t, const std::string& how) {
    for (int m = 0; m < M; ++m)
      for (size_t i = 0; i < P; ++i) {
        ASSERT_EQ(t.params[m * P + i], plain[m].params[i]) << m << " " << i << ", " << how;
        ASSERT_EQ(t.adam.m[m * P + i], plain[m].adam.m[i]) << m << " " << i << ", " << how;
        ASSERT_EQ(t.adam.v[m * P + i], plain[m].adam.v[i]) << m << " " << i << ", " << how;
      }
    EXPECT_NE(t.params, p0);
  };
  for (int threads : {1, 2}) {
    Trainer t(s, cfg, p0, M);
    for (int k = 0; k < steps; ++k) {
      const AdamStepScalars sc = adam_step_scalars(cfg, k + 1);
      for_each_model(M, threads, [&](int m) {
        step(t, m, sc, X.data(), rows_of(k, m), labels_of(k, m), B, 1);
      });
      for (int m = 0; m < M; ++m)
        EXPECT_EQ(t.losses[m], loss_plain[m][k]) << "model " << m << ", step " << k;
    }
    expect_equal(t, "lockstep on " + std::to_string(threads) + " threads");
  }
  for (int product_threads : {1, 2}) {
    Trainer each(s, cfg, p0, M);
    for (int m = M - 1; m >= 0; --m)
      for (int k = 0; k < steps; ++k) {
        const float l = step(each, m, adam_step_scalars(cfg, k + 1), X.data(), rows_of(k, m),
                             labels_of(k, m), B, product_threads);
        EXPECT_EQ(l, loss_plain[m][k]) << "model " << m << ", step " << k;
      }
    expect_equal(each, "model by model, products on " + std::to_string(product_threads));
  }
}

TEST(TrainStep, EachModelsStepEqualsThePlainStepInAnyOrderAndThreadCount) {
  // Preference heads (Bradley–Terry; a 6→70→1 head, and φ + head with φ's linear output).
  const float l2 = 0.5f;
  auto pref = [&](Trainer& t, int m, const AdamStepScalars& sc, const float* X,
                  const int32_t* pairs, const float* label, int B, int threads) {
    return preference_train_step(t, m, sc, X, pairs, label, B, l2, threads);
  };
  auto pref_loss = [&](const float* r, const float* label, int B, float* dr) {
    return bradley_terry_loss(r, label, B, l2, dr);
  };
  expect_each_model_equals_it_trained_plainly(MlpShape{{6, 70, 1}}, 2, pref, pref_loss);
  MlpShape unfrozen{{19, 40, 6, 40, 1}};
  unfrozen.linear_layers = {1};
  expect_each_model_equals_it_trained_plainly(unfrozen, 2, pref, pref_loss);
  // Triplets (an ensemble of φ): the label is unused.
  auto trip = [](Trainer& t, int m, const AdamStepScalars& sc, const float* X, const int32_t* trip,
                 const float*, int B,
                 int threads) { return triplet_train_step(t, m, sc, X, trip, B, 1.f, threads); };
  auto trip_loss = [](const float* emb, const float*, int B, float* demb) {
    return symmetric_triplet_loss(emb, B, 6, 1.f, demb);
  };
  expect_each_model_equals_it_trained_plainly(MlpShape{{19, 64, 64, 6}}, 3, trip, trip_loss);
}

// A model's parameters past the network's, which a one-network step does not use, get the
// update of a zero gradient (their moments decay; a moment of 0 leaves them where they are).
TEST(TrainStep, TrailingParametersAStepDoesNotUseGetAZeroGradientsUpdate) {
  const MlpShape s{{4, 8, 1}};
  const size_t P = s.param_count();
  Rng rng(3);
  std::vector<float> p(P + 2), X(10 * 4);
  mlp_init(s, p.data(), rng);
  p[P] = 0.5f, p[P + 1] = -0.25f;
  for (auto& v : X) v = float(rng.normal());
  Trainer t(s, AdamConfig{0.01, 1.0}, p);
  t.adam.m[P] = 0.1f;  // a moment left from earlier steps moves its parameter
  t.adam.v[P] = 0.04f;
  const int32_t pairs[4] = {0, 1, 2, 3};
  const float label[2] = {1, 0};
  preference_train_step(t, 0, adam_step_scalars(t.adam_cfg, 1), X.data(), pairs, label, 2, 0.f);
  std::vector<float> g(2, 0.f), pp{0.5f, -0.25f};
  AdamState ref(2);
  ref.m[0] = 0.1f, ref.v[0] = 0.04f;
  adam_step(t.adam_cfg, ref, pp.data(), g.data(), 2);
  EXPECT_EQ(t.params[P], pp[0]);
  EXPECT_NE(t.params[P], 0.5f);
  EXPECT_EQ(t.params[P + 1], -0.25f);
  EXPECT_EQ(t.adam.m[P], ref.m[0]);
}

TEST(TrainStep, RefusesParametersThatAreNotModelsTimesAModel) {
  const MlpShape s{{4, 8, 1}};
  const size_t P = s.param_count();
  EXPECT_THROW(Trainer(s, AdamConfig{}, std::vector<float>(P - 1)), std::invalid_argument);
  EXPECT_THROW(Trainer(s, AdamConfig{}, std::vector<float>(3 * P + 1), 3), std::invalid_argument);
  EXPECT_THROW(Trainer(s, AdamConfig{}, std::vector<float>(P), 0), std::invalid_argument);
  EXPECT_EQ(Trainer(s, AdamConfig{}, std::vector<float>(2 * P + 4), 2).stride, P + 2);
}

}  // namespace
}  // namespace sirl
