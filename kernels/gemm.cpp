#include "kernels/gemm.h"

#include <Eigen/Core>
#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <vector>

#ifdef SIRL_HAVE_XSMM
#include <libxsmm.h>
#endif

namespace sirl {
namespace {

template <typename T>
using RowMat = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
template <typename T>
using MapC = Eigen::Map<const RowMat<T>>;
template <typename T>
using Map = Eigen::Map<RowMat<T>>;

// C's columns are cut into fixed slices whatever the thread count (64 wide when N ≤ 256, e.g.
// the Grid nets' 128 units, so two threads still find work; 256 otherwise), and, for the libxsmm
// kernels, its rows into fixed blocks of kRowBlock: each block of C is one kernel call whose
// summation order depends on the block's shape only, so every result is bit-identical across
// thread counts; threads only decide who computes which slice.
constexpr int kRowBlock = 256;

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

// ---- Eigen: the generic path (any CPU; SIRL_KERNELS=generic forces it) ----

template <typename T>
void eigen_nt(T* C, const T* A, const T* B, int M, int N, int K, bool acc, int j0, int nj) {
  MapC<T> a(A, M, K), b(B, N, K);
  auto cs = Map<T>(C, M, N).middleCols(j0, nj);
  if (acc)
    cs.noalias() += a * b.middleRows(j0, nj).transpose();
  else
    cs.noalias() = a * b.middleRows(j0, nj).transpose();
}
template <typename T>
void eigen_tn(T* C, const T* A, const T* B, int M, int N, int K, bool acc, int j0, int nj) {
  MapC<T> a(A, K, M), b(B, K, N);
  auto cs = Map<T>(C, M, N).middleCols(j0, nj);
  if (acc)
    cs.noalias() += a.transpose() * b.middleCols(j0, nj);
  else
    cs.noalias() = a.transpose() * b.middleCols(j0, nj);
}
template <typename T>
void eigen_nn(T* C, const T* A, const T* B, int M, int N, int K, bool acc, int j0, int nj) {
  MapC<T> a(A, M, K), b(B, K, N);
  auto cs = Map<T>(C, M, N).middleCols(j0, nj);
  if (acc)
    cs.noalias() += a * b.middleCols(j0, nj);
  else
    cs.noalias() = a * b.middleCols(j0, nj);
}

// ---- libxsmm: JIT kernels for this CPU (docs/roofline.md: 1.3–3× Eigen on these shapes) ----
//
// libxsmm is column-major: a row-major C[M,N] is its Cᶜ[N,M], so C = op(A)·op(B) is computed as
// Cᶜ = op(Bᶜ)·op(Aᶜ) with the roles of A and B swapped. A slice [j0, j0+nj) of C's columns is a
// block of Cᶜ's rows (m = nj, ldc = N), and a block of C's rows is a block of Cᶜ's columns.
// libxsmm 1.17 has no kernel with a transposed first operand, which nt needs: nt transposes its
// slice of B into a scratch buffer first (nj·K floats, against 2·M·nj·K FLOPs).

bool use_xsmm() {
#ifdef SIRL_HAVE_XSMM
  static const bool on = [] {
    const char* v = std::getenv("SIRL_KERNELS");
    if (v && std::strcmp(v, "generic") == 0) return false;
    libxsmm_init();
    return true;
  }();
  return on;
#else
  return false;
#endif
}

#ifdef SIRL_HAVE_XSMM
// Cᶜ[m, n] (+)= op(Aᶜ)[m, k] · op(Bᶜ)[k, n], column-major, in blocks of kRowBlock columns of Cᶜ.
// Returns false when libxsmm has no kernel for the shape (the caller then uses Eigen).
bool xsmm_colmajor(const float* a, const float* b, float* c, int m, int n, int k, int lda, int ldb,
                   int ldc, bool trans_b, bool acc) {
  const float alpha = 1, beta = acc ? 1 : 0;
  const int flags = trans_b ? LIBXSMM_GEMM_FLAG_TRANS_B : 0;
  for (int n0 = 0; n0 < n; n0 += kRowBlock) {
    const libxsmm_blasint bm = m, bn = std::min(kRowBlock, n - n0), bk = k;
    const libxsmm_blasint la = lda, lb = ldb, lc = ldc;
    const libxsmm_smmfunction kernel =
        libxsmm_smmdispatch(bm, bn, bk, &la, &lb, &lc, &alpha, &beta, &flags, nullptr);
    if (!kernel) return false;
    // op(Bᶜ)'s columns n0.. : column-major Bᶜ [k, n] starts at b + n0·ldb; transposed, Bᶜ is
    // [n, k] and its rows n0.. start at b + n0.
    kernel(a, b + (trans_b ? n0 : size_t(n0) * ldb), c + size_t(n0) * ldc);
  }
  return true;
}

thread_local std::vector<float> t_scratch;  // nt's transposed slice of B
#endif

template <typename T>
bool fast_nt(T*, const T*, const T*, int, int, int, bool, int, int) {
  return false;
}
template <typename T>
bool fast_tn(T*, const T*, const T*, int, int, int, bool, int, int) {
  return false;
}
template <typename T>
bool fast_nn(T*, const T*, const T*, int, int, int, bool, int, int) {
  return false;
}

#ifdef SIRL_HAVE_XSMM
// C[M,N] (+)= A[M,K]·B[N,K]ᵀ, columns [j0, j0+nj): Bt[K, nj] = B[j0.., :]ᵀ, then Cᶜ = Btᶜ·Aᶜ.
template <>
bool fast_nt<float>(float* C, const float* A, const float* B, int M, int N, int K, bool acc, int j0,
                    int nj) {
  std::vector<float>& bt = t_scratch;
  bt.resize(size_t(K) * nj);
  for (int j = 0; j < nj; ++j)
    for (int k = 0; k < K; ++k) bt[size_t(k) * nj + j] = B[size_t(j0 + j) * K + k];
  return xsmm_colmajor(bt.data(), A, C + j0, nj, M, K, nj, K, N, false, acc);
}
// C[M,N] (+)= A[K,M]ᵀ·B[K,N]: Cᶜ = Bᶜ·(Aᶜ)ᵀ with Aᶜ = [M, K] column-major.
template <>
bool fast_tn<float>(float* C, const float* A, const float* B, int M, int N, int K, bool acc, int j0,
                    int nj) {
  return xsmm_colmajor(B + j0, A, C + j0, nj, M, K, N, M, N, true, acc);
}
// C[M,N] (+)= A[M,K]·B[K,N]: Cᶜ = Bᶜ·Aᶜ.
template <>
bool fast_nn<float>(float* C, const float* A, const float* B, int M, int N, int K, bool acc, int j0,
                    int nj) {
  return xsmm_colmajor(B + j0, A, C + j0, nj, M, K, N, K, N, false, acc);
}
#endif

}  // namespace

template <typename T>
void matmul_nt(T* C, const T* A, const T* B, int M, int N, int K, bool accumulate, int threads) {
  const bool fast = use_xsmm();
  for_column_slices(N, threads, [&](int j0, int nj) {
    if (!(fast && fast_nt<T>(C, A, B, M, N, K, accumulate, j0, nj)))
      eigen_nt<T>(C, A, B, M, N, K, accumulate, j0, nj);
  });
}

template <typename T>
void matmul_tn(T* C, const T* A, const T* B, int M, int N, int K, bool accumulate, int threads) {
  const bool fast = use_xsmm();
  for_column_slices(N, threads, [&](int j0, int nj) {
    if (!(fast && fast_tn<T>(C, A, B, M, N, K, accumulate, j0, nj)))
      eigen_tn<T>(C, A, B, M, N, K, accumulate, j0, nj);
  });
}

template <typename T>
void matmul_nn(T* C, const T* A, const T* B, int M, int N, int K, bool accumulate, int threads) {
  const bool fast = use_xsmm();
  for_column_slices(N, threads, [&](int j0, int nj) {
    if (!(fast && fast_nn<T>(C, A, B, M, N, K, accumulate, j0, nj)))
      eigen_nn<T>(C, A, B, M, N, K, accumulate, j0, nj);
  });
}

const char* gemm_backend() {
  return use_xsmm() ? "libxsmm" : "eigen";
}

#define SIRL_INSTANTIATE(T)                                                     \
  template void matmul_nt<T>(T*, const T*, const T*, int, int, int, bool, int); \
  template void matmul_tn<T>(T*, const T*, const T*, int, int, int, bool, int); \
  template void matmul_nn<T>(T*, const T*, const T*, int, int, int, bool, int);
SIRL_INSTANTIATE(float)
SIRL_INSTANTIATE(double)
#undef SIRL_INSTANTIATE

}  // namespace sirl
