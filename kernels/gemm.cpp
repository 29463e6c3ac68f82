#include "kernels/gemm.h"

#include <Eigen/Core>
#include <algorithm>

namespace sirl {
namespace {

template <typename T>
using RowMat = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
template <typename T>
using MapC = Eigen::Map<const RowMat<T>>;
template <typename T>
using Map = Eigen::Map<RowMat<T>>;

// C's columns are cut into fixed 256-wide slices whatever the thread count: Eigen picks its
// blocking (and so its summation order) from the slice shape, so fixed slices keep every
// result bit-identical across thread counts; threads only decide who computes which slice.
// Narrow matrices (N ≤ 256, e.g. the Grid nets' 128 units) use 64-wide slices so two threads
// still find work; the width depends on N only.
template <typename Fn>
void for_column_slices(int N, int threads, Fn&& fn) {
  const int kSlice = N <= 256 ? 64 : 256;
  const int slices = (N + kSlice - 1) / kSlice;
  if (threads <= 1 || slices <= 1) {
    for (int p = 0; p < slices; ++p) fn(p * kSlice, std::min(kSlice, N - p * kSlice));
    return;
  }
#pragma omp parallel for num_threads(threads) schedule(static)
  for (int p = 0; p < slices; ++p) fn(p * kSlice, std::min(kSlice, N - p * kSlice));
}

}  // namespace

template <typename T>
void matmul_nt(T* C, const T* A, const T* B, int M, int N, int K, bool accumulate, int threads) {
  MapC<T> a(A, M, K), b(B, N, K);
  Map<T> c(C, M, N);
  for_column_slices(N, threads, [&](int j0, int nj) {
    auto cs = c.middleCols(j0, nj);
    if (accumulate)
      cs.noalias() += a * b.middleRows(j0, nj).transpose();
    else
      cs.noalias() = a * b.middleRows(j0, nj).transpose();
  });
}

template <typename T>
void matmul_tn(T* C, const T* A, const T* B, int M, int N, int K, bool accumulate, int threads) {
  MapC<T> a(A, K, M), b(B, K, N);
  Map<T> c(C, M, N);
  for_column_slices(N, threads, [&](int j0, int nj) {
    auto cs = c.middleCols(j0, nj);
    if (accumulate)
      cs.noalias() += a.transpose() * b.middleCols(j0, nj);
    else
      cs.noalias() = a.transpose() * b.middleCols(j0, nj);
  });
}

template <typename T>
void matmul_nn(T* C, const T* A, const T* B, int M, int N, int K, bool accumulate, int threads) {
  MapC<T> a(A, M, K), b(B, K, N);
  Map<T> c(C, M, N);
  for_column_slices(N, threads, [&](int j0, int nj) {
    auto cs = c.middleCols(j0, nj);
    if (accumulate)
      cs.noalias() += a * b.middleCols(j0, nj);
    else
      cs.noalias() = a * b.middleCols(j0, nj);
  });
}

#define SIRL_INSTANTIATE(T)                                                     \
  template void matmul_nt<T>(T*, const T*, const T*, int, int, int, bool, int); \
  template void matmul_tn<T>(T*, const T*, const T*, int, int, int, bool, int); \
  template void matmul_nn<T>(T*, const T*, const T*, int, int, int, bool, int);
SIRL_INSTANTIATE(float)
SIRL_INSTANTIATE(double)
#undef SIRL_INSTANTIATE

}  // namespace sirl
