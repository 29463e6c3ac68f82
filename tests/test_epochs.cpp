// engine/epochs.h: PyTorch DataLoader(shuffle=True, drop_last=False) semantics, by hand.
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>

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

TEST(Epochs, TheBatchedFormGivesEachModelItsOwnOrderAndTheSameBatchSizes) {
  std::vector<Rng> rngs{Rng(1), Rng(2)};
  Rng solo(1);
  std::vector<int32_t> order0;
  std::vector<int> sizes;
  std::vector<float> losses(2);
  const auto curves = run_epochs_batched(
      7, 2, 3, rngs,
      [&](const std::vector<const int32_t*>& rows, int b) -> const std::vector<float>& {
        sizes.push_back(b);
        order0.insert(order0.end(), rows[0], rows[0] + b);
        losses = {1.0f, float(b)};
        return losses;
      });
  EXPECT_EQ(sizes, (std::vector<int>{3, 3, 1, 3, 3, 1}));
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

}  // namespace
}  // namespace sirl
