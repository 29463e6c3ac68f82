// Training checkpoints (engine/checkpoint.h): a training interrupted after a saved epoch and
// resumed from that snapshot ends with the same bits as one never interrupted — weights, curves
// and FLOP counts — for every kind of training (SIRL, preference pre-training, the VAE, TPA heads
// frozen and unfrozen). Saving alone changes nothing, and a snapshot that does not fit is refused.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>

#include <optional>
#include <stdexcept>
#include <string>

#include "engine/checkpoint.h"
#include "engine/methods.h"
#include "engine/tpa.h"
#include "engine/train_vae.h"
#include "tests/grid_world.h"
#include "tests/memory_checkpointer.h"

namespace sirl {
namespace {

using namespace test;

Hyper short_hyper() {
  Hyper h = fast_hyper();
  h.sirl.epochs = h.pref.epochs = h.tpa.epochs = 7;
  h.vae.epochs = 5;
  return h;
}

// Runs `train(ckpt)` three ways: plain; saving after every epoch; stopped after epoch `stop`
// and resumed from what it saved. Returns the three results.
template <typename Train>
auto three_ways(Train&& train, int stop) {
  auto plain = train(nullptr);
  MemoryCheckpointer every;
  auto saving = train(&every);
  EXPECT_GT(every.saves, 0) << "no epoch was saved";
  MemoryCheckpointer interrupted;
  interrupted.stop_after = stop;
  EXPECT_THROW(train(&interrupted), Interrupted);
  EXPECT_EQ(interrupted.saved->epoch, stop);
  interrupted.stop_after = -1;
  auto resumed = train(&interrupted);
  return std::make_tuple(plain, saving, resumed);
}

TEST(Checkpoint, SirlResumesBitIdentical) {
  const World& w = world();
  const auto [plain, saving, resumed] = three_ways(
      [&](Checkpointer* c) {
        const MethodConfig cfg{Method::sirl, 300, false, short_hyper()};
        return train_representation(w.d, w.bundle, cfg, 5, nullptr, {.checkpointer = c});
      },
      3);
  for (const Representation* r : {&saving, &resumed}) {
    EXPECT_EQ(r->params, plain.params);
    EXPECT_EQ(r->loss_curve, plain.loss_curve);
    EXPECT_EQ(r->train_flops, plain.train_flops);
  }
  EXPECT_EQ(plain.loss_curve.size(), 7u);
}

TEST(Checkpoint, PreferencePretrainingResumesBitIdentical) {
  const World& w = world();
  const auto [plain, saving, resumed] = three_ways(
      [&](Checkpointer* c) {
        const MethodConfig cfg{Method::multipref10, 300, false, short_hyper()};
        return train_representation(w.d, w.bundle, cfg, 5, nullptr, {.checkpointer = c});
      },
      5);
  for (const Representation* r : {&saving, &resumed}) {
    EXPECT_EQ(r->params, plain.params);
    EXPECT_EQ(r->heads, plain.heads);
    EXPECT_EQ(r->loss_curve, plain.loss_curve);
    EXPECT_EQ(r->train_flops, plain.train_flops);
  }
}

TEST(Checkpoint, VaeResumesBitIdentical) {
  const World& w = world();
  const auto [plain, saving, resumed] = three_ways(
      [&](Checkpointer* c) { return train_vae(w.d, short_hyper(), 11, {.checkpointer = c}); }, 2);
  for (const VaeModel* m : {&saving, &resumed}) {
    EXPECT_EQ(m->params, plain.params);
    EXPECT_EQ(m->loss_curve, plain.loss_curve);
    EXPECT_EQ(m->reconstruction_curve, plain.reconstruction_curve);
    EXPECT_EQ(m->kl_curve, plain.kl_curve);
    EXPECT_EQ(m->latent_mean, plain.latent_mean);
    EXPECT_EQ(m->train_flops, plain.train_flops);
  }
  EXPECT_EQ(plain.kl_curve.size(), 5u);
}

TEST(Checkpoint, TpaHeadsFrozenAndUnfrozenResumeBitIdentical) {
  const World& w = world();
  // The heads train one after another in stretches of epochs (M = 20 < one batch: one step an
  // epoch), checkpoints between stretches: every epoch (stretch 1), every second (stretch 2).
  for (bool frozen : {true, false})
    for (int stretch : {1, 2}) {
      const auto [plain, saving, resumed] = three_ways(
          [&](Checkpointer* c) {
            const TpaConfig cfg{20, frozen, short_hyper()};
            return evaluate_tpa(trained().sirl, w.d, w.bundle.tpa, cfg, 3,
                                {.checkpointer = c, .stretch_steps = stretch});
          },
          4);
      for (const TpaResult* r : {&saving, &resumed}) {
        EXPECT_EQ(r->accuracy, plain.accuracy) << "frozen " << frozen << ", stretch " << stretch;
        EXPECT_EQ(r->loss_curves, plain.loss_curves) << "frozen " << frozen;
        EXPECT_EQ(r->phi_drift, plain.phi_drift) << "frozen " << frozen;
        EXPECT_EQ(r->train_flops, plain.train_flops) << "frozen " << frozen;
      }
    }
}

// With the converged stopping rule, heads stop at different epochs; a resume must know which
// heads had stopped (and where), or it would train them again.
TEST(Checkpoint, ConvergedHeadsResumeBitIdenticalWithTheirStoppingEpochs) {
  const World& w = world();
  const Hyper h = stopping_hyper(200, "converged");
  auto run = [&](Checkpointer* c) {
    const TpaConfig cfg{20, true, h};
    // One step an epoch: a save after every epoch.
    return evaluate_tpa(trained().sirl, w.d, w.bundle.tpa, cfg, 3,
                        {.checkpointer = c, .stretch_steps = 1});
  };
  // Interrupted right after the first head stopped (a stop at a stretch's end) and one epoch
  // later, while other heads still train.
  const TpaResult first = run(nullptr);
  const int lo = *std::min_element(first.head_epochs.begin(), first.head_epochs.end());
  const int hi = *std::max_element(first.head_epochs.begin(), first.head_epochs.end());
  ASSERT_LT(lo + 1, hi) << "the heads stop too close together for this test";
  for (int stop : {lo, lo + 1}) {
    const auto [plain, saving, resumed] = three_ways(run, stop);
    for (const TpaResult* r : {&saving, &resumed}) {
      EXPECT_EQ(r->head_epochs, plain.head_epochs) << "interrupted after epoch " << stop;
      EXPECT_EQ(r->accuracy, plain.accuracy) << "interrupted after epoch " << stop;
      EXPECT_EQ(0, std::memcmp(r->loss_curves.data(), plain.loss_curves.data(),
                               plain.loss_curves.size() * sizeof(float)));
      EXPECT_EQ(r->train_flops, plain.train_flops);
    }
  }
}

TEST(Checkpoint, TheLastEpochIsNeverSavedAndResumingChangesTheOutcomeOnlyByTheSavedState) {
  // Saves come after epochs 1..E−1 (the finished training is the task's commit, not a snapshot).
  const World& w = world();
  MemoryCheckpointer c;
  const MethodConfig cfg{Method::sirl, 300, false, short_hyper()};
  const Execution with_c{.checkpointer = &c};
  train_representation(w.d, w.bundle, cfg, 5, nullptr, with_c);
  EXPECT_EQ(c.saves, 6);
  EXPECT_EQ(c.saved->epoch, 6);
  // A snapshot whose weights were perturbed resumes from those weights: the result differs, so
  // the resume really starts from the snapshot rather than recomputing from scratch.
  const Representation plain =
      train_representation(w.d, w.bundle, MethodConfig{Method::sirl, 300, false, short_hyper()}, 5);
  c.saved->floats["sirl/params"][0] += 0.5f;
  EXPECT_NE(train_representation(w.d, w.bundle, cfg, 5, nullptr, with_c).params, plain.params);
}

TEST(Checkpoint, ASnapshotThatDoesNotFitIsRefused) {
  const World& w = world();
  MemoryCheckpointer c;
  const MethodConfig cfg{Method::sirl, 300, false, short_hyper()};
  const Execution with_c{.checkpointer = &c};
  c.stop_after = 2;
  EXPECT_THROW(train_representation(w.d, w.bundle, cfg, 5, nullptr, with_c), Interrupted);
  c.stop_after = -1;
  TrainingSnapshot good = *c.saved;
  c.saved->floats["sirl/adam_m"].pop_back();  // weights of another shape
  try {
    train_representation(w.d, w.bundle, cfg, 5, nullptr, with_c);
    FAIL() << "a snapshot with the wrong shapes was applied";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("sirl/adam_m"), std::string::npos) << e.what();
  }
  c.saved = good;
  c.saved->epoch = 7;  // as many as the training has: not a snapshot this training writes
  EXPECT_THROW(train_representation(w.d, w.bundle, cfg, 5, nullptr, with_c), std::runtime_error);
  c.saved = good;
  c.saved->words.erase("loop/order/0");
  EXPECT_THROW(train_representation(w.d, w.bundle, cfg, 5, nullptr, with_c), std::runtime_error);
}

// A single training's snapshot as engines up to 0.12 wrote it (its curve so far as "loop/curve",
// its order stream as "loop/order") resumes to the uninterrupted run's bits.
TEST(Checkpoint, AnOlderSingleModelSnapshotResumesToTheSameBits) {
  const World& w = world();
  const MethodConfig cfg{Method::sirl, 300, false, short_hyper()};
  const Representation plain = train_representation(w.d, w.bundle, cfg, 5, nullptr, {});
  MemoryCheckpointer c;
  const Execution with_c{.checkpointer = &c};
  c.stop_after = 2;
  EXPECT_THROW(train_representation(w.d, w.bundle, cfg, 5, nullptr, with_c), Interrupted);
  c.stop_after = -1;
  TrainingSnapshot& s = *c.saved;
  ASSERT_GT(s.epoch, 0);
  const std::vector<float>& curves = s.floats.at("loop/curves");
  s.floats["loop/curve"].assign(curves.begin(), curves.begin() + s.epoch);
  s.words["loop/order"] = s.words.at("loop/order/0");
  for (const char* k : {"loop/curves", "loop/epochs_run", "loop/stopped"}) s.floats.erase(k);
  s.words.erase("loop/order/0");
  const Representation resumed = train_representation(w.d, w.bundle, cfg, 5, nullptr, with_c);
  EXPECT_EQ(resumed.params, plain.params);
  EXPECT_EQ(resumed.loss_curve, plain.loss_curve);
  EXPECT_EQ(resumed.train_flops, plain.train_flops);
}

}  // namespace
}  // namespace sirl
