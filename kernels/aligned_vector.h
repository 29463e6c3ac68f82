// std::vector whose storage starts on a 64-byte boundary: one cache line, one AVX-512 vector.
// The GEMM kernels load 16 floats at a time along rows of activations, weights and scratch. malloc
// aligns to 16 bytes, so unless a buffer happened to start on a cache line (one time in four),
// every such load along its 64-byte-multiple rows straddled two lines, which cost libxsmm's
// 192 × 128 × 128 product 12 % (docs/roofline.md). Alignment changes no result: the kernels run
// the same instructions on the same values.
#pragma once

#include <cstddef>
#include <new>
#include <vector>

namespace sirl {

template <typename T>
struct CacheLineAllocator {
  using value_type = T;
  static constexpr std::align_val_t kAlign{64};
  CacheLineAllocator() = default;
  template <typename U>
  CacheLineAllocator(const CacheLineAllocator<U>&) noexcept {}
  T* allocate(size_t n) { return static_cast<T*>(::operator new(n * sizeof(T), kAlign)); }
  void deallocate(T* p, size_t) noexcept { ::operator delete(p, kAlign); }
  template <typename U>
  bool operator==(const CacheLineAllocator<U>&) const noexcept {
    return true;
  }
};

template <typename T>
using AlignedVector = std::vector<T, CacheLineAllocator<T>>;

}  // namespace sirl
