// engine/epochs.h: PyTorch DataLoader(shuffle=True, drop_last=False) semantics, by hand.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

#include "engine/epochs.h"

namespace sirl {
namespace {

TEST(Epochs, EveryExampleOncePerEpochInBatchesWithAShortLastOne) {
  // n = 10, batch 4: batches of 4, 4 and 2; each epoch a permutation of 0..9. The step returns
  // the batch's first index as its "loss", so the epoch mean is Σ b·first / n, checked by hand.
  Rng rng(5);
  std::vector<std::vector<int>> sizes(3);
  std::vector<double> expected;
  int epoch = 0;
  std::vector<int> seen;
  double sum = 0;
  const auto curve = run_epochs(10, 3, 4, rng, [&](const int32_t* rows, int b) {
    sizes[epoch].push_back(b);
    seen.insert(seen.end(), rows, rows + b);
    sum += double(rows[0]) * b;
    if (seen.size() == 10) {
      std::vector<int> sorted = seen;
      std::sort(sorted.begin(), sorted.end());
      std::vector<int> all(10);
      std::iota(all.begin(), all.end(), 0);
      EXPECT_EQ(sorted, all) << "epoch " << epoch << " is not a permutation";
      expected.push_back(sum / 10);
      seen.clear();
      sum = 0;
      ++epoch;
    }
    return float(rows[0]);
  });
  ASSERT_EQ(epoch, 3);
  for (const auto& s : sizes) EXPECT_EQ(s, (std::vector<int>{4, 4, 2}));
  ASSERT_EQ(curve.size(), 3u);
  for (int e = 0; e < 3; ++e) EXPECT_FLOAT_EQ(curve[e], float(expected[e]));
}

TEST(Epochs, EveryModelDrawsItsOwnOrderFromItsStreamInTheSameBatchSizes) {
  std::vector<Rng> rngs{Rng(1), Rng(2)};
  Rng solo(1);
  std::vector<int32_t> order0;
  std::vector<std::vector<int>> sizes(2);
  EpochLoopOptions lockstep;
  lockstep.stretch_steps = 0;  // one epoch a stretch
  const auto curves = run_model_epochs(
                          7, 2, 3, rngs,
                          [&](int m, const int32_t* rows, int b, int64_t) {
                            sizes[m].push_back(b);
                            if (m == 0) order0.insert(order0.end(), rows, rows + b);
                            return m == 0 ? 1.0f : float(b);
                          },
                          [](int) {}, lockstep)
                          .curves;
  for (int m = 0; m < 2; ++m) EXPECT_EQ(sizes[m], (std::vector<int>{3, 3, 1, 3, 3, 1}));
  // Model 0's order is what one model with the same stream would draw.
  std::vector<int32_t> expect, o;
  for (int e = 0; e < 2; ++e) {
    shuffle_order(7, solo, o);
    expect.insert(expect.end(), o.begin(), o.end());
  }
  EXPECT_EQ(order0, expect);
  // curves [R, epochs]: model 0's loss 1 always; model 1's Σ b·b / n = (9 + 9 + 1) / 7.
  ASSERT_EQ(curves.size(), 4u);
  EXPECT_FLOAT_EQ(curves[0], 1.0f);
  EXPECT_FLOAT_EQ(curves[1], 1.0f);
  EXPECT_FLOAT_EQ(curves[2], 19.0f / 7);
  EXPECT_FLOAT_EQ(curves[3], 19.0f / 7);
}

// A toy training for the loop tests: each model's state folds in every batch it sees and the
// step number it is told, in order, so any change of order, rows or numbering changes it.
struct ToyModels {
  std::vector<uint64_t> state;
  explicit ToyModels(int R) : state(R, 1) {}
  float step(int m, const int32_t* rows, int b, int64_t t) {
    uint64_t& s = state[m];
    for (int i = 0; i < b; ++i) s = s * 1000003u + uint64_t(rows[i]) + 7;
    s = s * 31 + uint64_t(t);
    return float(s % 1000) / 8;
  }
};

TEST(Epochs, EveryModelTakesTheStepsOfAHandWrittenLoopWhateverTheStretchAndThreadCount) {
  const int R = 3, epochs = 5, batch = 3;
  const int64_t n = 7;  // 3 batches an epoch: 3, 3, 1
  // The reference, written out: every epoch each model shuffles from its own stream and takes
  // its batches, its steps numbered from 1; curves [R, epochs] of the b-weighted mean loss.
  std::vector<Rng> rngs_b{Rng(1), Rng(2), Rng(3)};
  ToyModels ref(R);
  std::vector<float> curves_b(size_t(R) * epochs);
  std::vector<int64_t> t(R, 0);
  for (int e = 0; e < epochs; ++e)
    for (int m = 0; m < R; ++m) {
      std::vector<int32_t> order;
      shuffle_order(n, rngs_b[m], order);
      double sum = 0;
      for (int64_t i0 = 0; i0 < n; i0 += batch) {
        const int b = int(std::min<int64_t>(batch, n - i0));
        sum += double(ref.step(m, order.data() + i0, b, ++t[m])) * b;
      }
      curves_b[size_t(m) * epochs + e] = float(sum / double(n));
    }
  ASSERT_EQ(t[0], epochs * 3);
  for (int threads : {1, 2})
    for (int stretch : {1, 4, 100}) {  // 1 epoch, 2 epochs (4 steps), all epochs
      std::vector<Rng> rngs{Rng(1), Rng(2), Rng(3)};
      ToyModels toy(R);
      std::vector<int> at;
      EpochLoopOptions opt;
      opt.threads = threads;
      opt.stretch_steps = stretch;
      const auto curves = run_model_epochs(
                              n, epochs, batch, rngs,
                              [&](int m, const int32_t* rows, int b, int64_t step) {
                                return toy.step(m, rows, b, step);
                              },
                              [&](int e) { at.push_back(e); }, opt)
                              .curves;
      EXPECT_EQ(toy.state, ref.state) << "stretch " << stretch << ", threads " << threads;
      EXPECT_EQ(curves, curves_b) << "stretch " << stretch << ", threads " << threads;
      const std::vector<int> expect_at = stretch == 1   ? std::vector<int>{1, 2, 3, 4, 5}
                                         : stretch == 4 ? std::vector<int>{2, 4, 5}
                                                        : std::vector<int>{5};
      EXPECT_EQ(at, expect_at) << "stretch " << stretch;
      for (int m = 0; m < R; ++m)  // the order streams end where the reference left them
        EXPECT_EQ(rngs[m].uniform_int(1000000), Rng(rngs_b[m]).uniform_int(1000000));
    }
}

// Models whose loss is flat from an epoch of their own on (model m: 100 − e before epoch 10 + 15m,
// then 1) stop where the rule says on their own curves; each stopped model's state is that of a
// fixed run of that many epochs, whatever the threads and stretches, and its curve is NaN after.
TEST(Epochs, EachModelStopsOnItsOwnCurveWithTheFixedRunsBitsWhateverTheThreadCount) {
  const int R = 3, epochs = 120, batch = 3;
  const int64_t n = 7;  // 3 steps an epoch
  StopRule rule;
  rule.converged = true;
  rule.min_epochs = 5;
  auto loss = [](int m, int64_t t) {  // step t (1-based) is in epoch (t − 1) / 3
    const int e = int((t - 1) / 3);
    return e < 10 + 15 * m ? float(100 - e) : 1.f;
  };
  // Where the rule stops each model, from its curve alone.
  std::vector<int> expect_epochs(R, epochs);
  for (int m = 0; m < R; ++m) {
    std::vector<float> c;
    for (int e = 0; e < epochs; ++e) {
      c.push_back(loss(m, int64_t(e) * 3 + 1));
      if (e + 1 < epochs && stops_after(rule, c.data(), e + 1)) {
        expect_epochs[m] = e + 1;
        break;
      }
    }
    ASSERT_LT(expect_epochs[m], epochs);
  }
  EXPECT_LT(expect_epochs[0], expect_epochs[1]);
  for (int threads : {1, 2})
    for (int stretch : {1, 4, 1000}) {
      std::vector<Rng> rngs{Rng(1), Rng(2), Rng(3)};
      ToyModels toy(R);
      EpochLoopOptions opt;
      opt.threads = threads;
      opt.stretch_steps = stretch;
      opt.stop = rule;
      const ModelCurves out = run_model_epochs(
          n, epochs, batch, rngs,
          [&](int m, const int32_t* rows, int b, int64_t t) {
            toy.step(m, rows, b, t);
            return loss(m, t);
          },
          [](int) {}, opt);
      EXPECT_EQ(out.epochs_run, expect_epochs) << threads << " threads, stretch " << stretch;
      for (int m = 0; m < R; ++m) {
        // The reference: model m alone, a fixed run of its epochs.
        std::vector<Rng> one{Rng(uint64_t(m + 1))};
        ToyModels ref(1);
        run_model_epochs(
            n, expect_epochs[m], batch, one,
            [&](int, const int32_t* rows, int b, int64_t t) { return ref.step(0, rows, b, t); },
            [](int) {});
        EXPECT_EQ(toy.state[m], ref.state[0]) << "model " << m << ", stretch " << stretch;
        for (int e = 0; e < epochs; ++e) {
          const float v = out.curves[size_t(m) * epochs + e];
          if (e < expect_epochs[m])
            EXPECT_EQ(v, loss(m, int64_t(e) * 3 + 1));
          else
            EXPECT_TRUE(std::isnan(v)) << "model " << m << ", epoch " << e;
        }
      }
    }
}

// The exact skip: when the training says it stands at a fixed point, the loop ends and the
// remaining epochs repeat the last loss; otherwise every epoch runs.
TEST(Epochs, AFixedPointEndsTheLoopAndFillsTheCurveWithItsLoss) {
  Rng rng(3);
  int steps = 0;
  std::vector<int> asked;
  const auto curve = run_epochs(
      4, 10, 2, rng, [&](const int32_t*, int) { return float(++steps > 6 ? 0 : 7 - steps); },
      nullptr,
      [&](int done) {
        asked.push_back(done);
        return done == 4;  // epochs 1..4 run: 8 steps, losses (6 5) (4 3) (2 1) (0 0)
      });
  EXPECT_EQ(steps, 8);
  EXPECT_EQ(asked, (std::vector<int>{1, 2, 3, 4}));
  EXPECT_EQ(curve, (std::vector<float>{5.5f, 3.5f, 1.5f, 0, 0, 0, 0, 0, 0, 0}));
  Rng rng2(3);
  int all = 0;
  const auto never = run_epochs(
      4, 10, 2, rng2, [&](const int32_t*, int) { return float(++all); }, nullptr,
      [](int) { return false; });
  EXPECT_EQ(all, 20);
  EXPECT_EQ(never.size(), 10u);
}

// Among several models, one at its fixed point stops stepping and repeats its last loss; the
// others run every epoch, whatever the threads and stretch.
TEST(Epochs, AModelAtItsFixedPointStopsAloneAndKeepsItsLastLoss) {
  for (int threads : {1, 2})
    for (int stretch : {0, 5}) {
      std::vector<Rng> rngs{Rng(1), Rng(2)};
      std::vector<int> steps(2, 0);
      EpochLoopOptions opt;
      opt.threads = threads;
      opt.stretch_steps = stretch;
      opt.at_fixed_point = [](int m, int done) { return m == 1 && done == 3; };
      const ModelCurves out = run_model_epochs(
          4, 6, 2, rngs, [&](int m, const int32_t*, int, int64_t) { return float(++steps[m]); },
          [](int) {}, opt);
      EXPECT_EQ(steps, (std::vector<int>{12, 6})) << threads << " threads, stretch " << stretch;
      EXPECT_EQ(out.epochs_run, (std::vector<int>{6, 3}));
      // Model 1's epochs: steps (1 2) (3 4) (5 6), then its last loss 5.5 repeated.
      const std::vector<float> c1(out.curves.begin() + 6, out.curves.end());
      EXPECT_EQ(c1, (std::vector<float>{1.5f, 3.5f, 5.5f, 5.5f, 5.5f, 5.5f}));
    }
}

TEST(Epochs, AStepThatThrowsInTheModelByModelLoopReachesTheCallerWhateverTheThreadCount) {
  // Models 1 and 2 fail at their second step; the lowest model's exception comes out, and no
  // checkpoint of the half-done stretch is taken (at_epoch is not called).
  for (int threads : {1, 2}) {
    std::vector<Rng> rngs{Rng(1), Rng(2), Rng(3)};
    int at_epochs = 0;
    try {
      EpochLoopOptions opt;
      opt.threads = threads;
      run_model_epochs(
          4, 3, 2, rngs,
          [&](int m, const int32_t*, int, int64_t t) -> float {
            if (m > 0 && t == 2) throw std::runtime_error("model " + std::to_string(m));
            return 0.f;
          },
          [&](int) { ++at_epochs; }, opt);
      ADD_FAILURE() << "no exception, threads " << threads;
    } catch (const std::runtime_error& e) {
      EXPECT_STREQ(e.what(), "model 1") << "threads " << threads;
    }
    EXPECT_EQ(at_epochs, 0);
  }
}

}  // namespace
}  // namespace sirl
