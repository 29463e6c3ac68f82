#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "engine/for_each_model.h"
#include "engine/train_step.h"
#include "kernels/rng.h"

namespace sirl {
namespace {

// The per-model steps of a BatchedTrainer (M models side by side: a TPA cell's heads, an ensemble
// of φ) against each model trained alone by the single-model step (a Trainer of its own, whose
// step runs its own code path) on its own rows: the parameters and both Adam moments must agree
// to the bit, and each model's loss too. The models take their steps two ways: all models' step k
// before any model's k + 1 (over 1 and 2 threads), and model after model, in reverse, each its
// steps in a row (as the epoch loop's stretches do). Three steps with a decaying rate, so the
// moments carry over and a wrong step number shows.
template <typename OfModel, typename Alone>
void expect_each_model_equals_it_alone(const MlpShape& s, int roles, OfModel&& of_model,
                                       Alone&& alone) {
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

  std::vector<Trainer> one;
  std::vector<std::vector<float>> loss_one(M);
  for (int m = 0; m < M; ++m) {
    one.emplace_back(s, cfg, std::vector<float>(p0.begin() + m * P, p0.begin() + (m + 1) * P));
    for (int k = 0; k < steps; ++k)
      loss_one[m].push_back(alone(one[m], X.data(), rows_of(k, m), labels_of(k, m), B));
  }
  auto expect_equal = [&](const BatchedTrainer& t, const std::string& how) {
    for (int m = 0; m < M; ++m)
      for (size_t i = 0; i < P; ++i) {
        ASSERT_EQ(t.params[m * P + i], one[m].params[i]) << m << " " << i << ", " << how;
        ASSERT_EQ(t.adam.m[m * P + i], one[m].adam.m[i]) << m << " " << i << ", " << how;
        ASSERT_EQ(t.adam.v[m * P + i], one[m].adam.v[i]) << m << " " << i << ", " << how;
      }
    EXPECT_NE(t.params, p0);
  };
  for (int threads : {1, 2}) {
    BatchedTrainer t(s, M, cfg, p0);
    for (int k = 0; k < steps; ++k) {
      const AdamStepScalars sc = adam_step_scalars(cfg, k + 1);
      for_each_model(M, threads, [&](int m) {
        of_model(t, m, sc, X.data(), rows_of(k, m), labels_of(k, m), B);
      });
      for (int m = 0; m < M; ++m)
        EXPECT_EQ(t.losses[m], loss_one[m][k]) << "model " << m << ", step " << k;
    }
    expect_equal(t, "lockstep on " + std::to_string(threads) + " threads");
  }
  BatchedTrainer each(s, M, cfg, p0);
  for (int m = M - 1; m >= 0; --m)
    for (int k = 0; k < steps; ++k) {
      const float loss = of_model(each, m, adam_step_scalars(cfg, k + 1), X.data(), rows_of(k, m),
                                  labels_of(k, m), B);
      EXPECT_EQ(loss, loss_one[m][k]) << "model " << m << ", step " << k;
    }
  expect_equal(each, "model by model");
}

TEST(TrainStep, EachModelsStepEqualsTheModelTrainedAloneInAnyOrderAndThreadCount) {
  // Preference heads (Bradley–Terry; a 6→70→1 head, and φ + head with φ's linear output).
  const float l2 = 0.5f;
  auto pref = [&](BatchedTrainer& t, int m, const AdamStepScalars& sc, const float* X,
                  const int32_t* pairs, const float* label, int B) {
    return preference_train_step_of_model(t, m, sc, X, pairs, label, B, l2);
  };
  auto pref_alone = [&](Trainer& t, const float* X, const int32_t* pairs, const float* label,
                        int B) { return preference_train_step(t, X, pairs, label, B, l2); };
  expect_each_model_equals_it_alone(MlpShape{{6, 70, 1}}, 2, pref, pref_alone);
  MlpShape unfrozen{{19, 40, 6, 40, 1}};
  unfrozen.linear_layers = {1};
  expect_each_model_equals_it_alone(unfrozen, 2, pref, pref_alone);
  // Triplets (an ensemble of φ): the label is unused.
  auto trip = [](BatchedTrainer& t, int m, const AdamStepScalars& sc, const float* X,
                 const int32_t* trip, const float*,
                 int B) { return triplet_train_step_of_model(t, m, sc, X, trip, B, 1.f); };
  auto trip_alone = [](Trainer& t, const float* X, const int32_t* trip, const float*, int B) {
    return triplet_train_step(t, X, trip, B, 1.f);
  };
  expect_each_model_equals_it_alone(MlpShape{{19, 64, 64, 6}}, 3, trip, trip_alone);
}

}  // namespace
}  // namespace sirl
