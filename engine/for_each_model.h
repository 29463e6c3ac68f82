// fn(m) for every one of M independent models, split over OpenMP threads: the TPA heads of a
// cell, the members of an ensemble. Which thread runs which model never changes a result, as the
// models share nothing they write.
#pragma once
#include <algorithm>
#include <exception>
#include <vector>

namespace sirl {

// An exception may not leave an OpenMP region (it would end the process): one from fn(m) (out of
// memory, say) is kept, the other models finish, and the lowest model's is rethrown here.
// On one thread there is no OpenMP region at all, not even a serialised one (`if (false)`): inside
// one, a model's own parallel kernels (a VAE's products over `threads` cores) would be a nested
// region, which OpenMP runs on one thread by default.
template <typename Fn>
void for_each_model(int M, int threads, Fn&& fn) {
  std::vector<std::exception_ptr> failed(size_t(std::max(M, 0)));
  const auto one = [&](int m) {
    try {
      fn(m);
    } catch (...) {
      failed[m] = std::current_exception();
    }
  };
  if (threads > 1 && M > 1) {
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int m = 0; m < M; ++m) one(m);
  } else {
    for (int m = 0; m < M; ++m) one(m);
  }
  for (const std::exception_ptr& f : failed)
    if (f) std::rethrow_exception(f);
}

}  // namespace sirl
