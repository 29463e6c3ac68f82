// Mini-batch order for one epoch, as PyTorch's DataLoader(shuffle=True, drop_last=False):
// a fresh permutation of the n examples each epoch, cut into batches of `batch` (the last one
// shorter when batch does not divide n).
#pragma once
#include <cstdint>
#include <numeric>
#include <utility>
#include <vector>

#include "kernels/rng.h"

namespace sirl {

// Fisher–Yates shuffle of 0..n−1 into `order` (resized).
inline void shuffle_order(int64_t n, Rng& rng, std::vector<int32_t>& order) {
  order.resize(n);
  std::iota(order.begin(), order.end(), 0);
  for (int64_t i = n - 1; i > 0; --i) std::swap(order[i], order[rng.uniform_int(uint64_t(i + 1))]);
}

inline int64_t batches_per_epoch(int64_t n, int batch) {
  return (n + batch - 1) / batch;
}

}  // namespace sirl
