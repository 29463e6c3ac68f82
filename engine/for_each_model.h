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
template <typename Fn>
void for_each_model(int M, int threads, Fn&& fn) {
  std::vector<std::exception_ptr> failed(size_t(std::max(M, 0)));
#pragma omp parallel for num_threads(std::max(1, threads)) schedule(static) if (threads > 1)
  for (int m = 0; m < M; ++m) {
    try {
      fn(m);
    } catch (...) {
      failed[m] = std::current_exception();
    }
  }
  for (const std::exception_ptr& f : failed)
    if (f) std::rethrow_exception(f);
}

}  // namespace sirl
