#include <gtest/gtest.h>

#include <vector>

#include "engine/train_step.h"
#include "kernels/rng.h"

namespace sirl {
namespace {

// The batched steps (M models side by side: a TPA cell's heads, an ensemble of φ) against each
// model trained alone by the single-model step on its own rows: the parameters and both Adam
// moments must agree to the bit, and each model's loss too, on 1 and 2 threads. Three steps, so
// the moments carry over.
template <typename Batched, typename Alone>
void expect_batched_equals_alone(const MlpShape& s, int roles, Batched&& batched, Alone&& alone) {
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
  const AdamConfig cfg{0.01, 0.999};

  std::vector<Trainer> one;
  std::vector<std::vector<float>> loss_one(M);
  for (int m = 0; m < M; ++m) {
    one.emplace_back(s, cfg, std::vector<float>(p0.begin() + m * P, p0.begin() + (m + 1) * P));
    for (int k = 0; k < steps; ++k)
      loss_one[m].push_back(alone(one[m], X.data(), idx.data() + (size_t(k) * M + m) * B * roles,
                                  label.data() + (size_t(k) * M + m) * B, B));
  }
  for (int threads : {1, 2}) {
    BatchedTrainer t(s, M, cfg, p0);
    for (int k = 0; k < steps; ++k) {
      batched(t, X.data(), idx.data() + size_t(k) * M * B * roles, label.data() + size_t(k) * M * B,
              B, threads);
      for (int m = 0; m < M; ++m)
        EXPECT_EQ(t.losses[m], loss_one[m][k]) << "model " << m << ", step " << k;
    }
    for (int m = 0; m < M; ++m)
      for (size_t i = 0; i < P; ++i) {
        ASSERT_EQ(t.params[m * P + i], one[m].params[i]) << m << " " << i << ", " << threads;
        ASSERT_EQ(t.adam.m[m * P + i], one[m].adam.m[i]) << m << " " << i;
        ASSERT_EQ(t.adam.v[m * P + i], one[m].adam.v[i]) << m << " " << i;
      }
    EXPECT_NE(t.params, p0);
  }
}

TEST(TrainStep, BatchedStepsEqualEachModelAloneWhateverTheThreadCount) {
  // Preference heads (Bradley–Terry; a 6→70→1 head, and φ + head with φ's linear output).
  const float l2 = 0.5f;
  auto pref_batched = [&](BatchedTrainer& t, const float* X, const int32_t* pairs,
                          const float* label, int B, int threads) {
    return preference_train_step_batched(t, X, pairs, label, B, l2, threads);
  };
  auto pref_alone = [&](Trainer& t, const float* X, const int32_t* pairs, const float* label,
                        int B) { return preference_train_step(t, X, pairs, label, B, l2); };
  expect_batched_equals_alone(MlpShape{{6, 70, 1}}, 2, pref_batched, pref_alone);
  MlpShape unfrozen{{19, 40, 6, 40, 1}};
  unfrozen.linear_layers = {1};
  expect_batched_equals_alone(unfrozen, 2, pref_batched, pref_alone);
  // Triplets (an ensemble of φ): the label is unused.
  auto trip_batched = [](BatchedTrainer& t, const float* X, const int32_t* trip, const float*,
                         int B, int threads) {
    return triplet_train_step_batched(t, X, trip, B, 1.f, threads);
  };
  auto trip_alone = [](Trainer& t, const float* X, const int32_t* trip, const float*, int B) {
    return triplet_train_step(t, X, trip, B, 1.f);
  };
  expect_batched_equals_alone(MlpShape{{19, 64, 64, 6}}, 3, trip_batched, trip_alone);
}

TEST(TrainStep, APreferenceModelSteppedAloneAtItsOwnPaceEqualsTheBatchedStep) {
  // preference_train_step_of_model, as run_epochs_model_by_model calls it: model after model (in
  // reverse, each its three steps in a row) with Adam's scalars by step number, against every
  // model stepped at once by preference_train_step_batched.
  MlpShape s{{19, 40, 6, 40, 1}};
  s.linear_layers = {1};
  const int M = 3, B = 5, T = 30, steps = 3;
  const size_t P = s.param_count();
  Rng rng(8);
  std::vector<float> X(size_t(T) * s.in()), p0(M * P);
  for (auto& v : X) v = float(rng.normal());
  for (int m = 0; m < M; ++m) mlp_init(s, p0.data() + m * P, rng);
  std::vector<int32_t> pairs(size_t(steps) * M * B * 2);
  std::vector<float> label(size_t(steps) * M * B);
  for (auto& v : pairs) v = int32_t(rng.uniform_int(T));
  for (auto& v : label) v = float(rng.uniform_int(2));
  const AdamConfig cfg{0.01, 0.99};  // a decaying rate, so a wrong step number shows
  BatchedTrainer all(s, M, cfg, p0), each(s, M, cfg, p0);
  std::vector<float> loss_all;
  for (int k = 0; k < steps; ++k) {
    preference_train_step_batched(all, X.data(), pairs.data() + size_t(k) * M * B * 2,
                                  label.data() + size_t(k) * M * B, B, 0.5f);
    loss_all.insert(loss_all.end(), all.losses.begin(), all.losses.end());
  }
  for (int m = M - 1; m >= 0; --m)
    for (int k = 0; k < steps; ++k) {
      const float loss =
          preference_train_step_of_model(each, m, adam_step_scalars(cfg, k + 1), X.data(),
                                         pairs.data() + (size_t(k) * M + m) * B * 2,
                                         label.data() + (size_t(k) * M + m) * B, B, 0.5f);
      EXPECT_EQ(loss, loss_all[size_t(k) * M + m]) << "model " << m << ", step " << k;
    }
  EXPECT_EQ(each.params, all.params);
  EXPECT_EQ(each.adam.m, all.adam.m);
  EXPECT_EQ(each.adam.v, all.adam.v);
  EXPECT_NE(each.params, p0);
}

}  // namespace
}  // namespace sirl
