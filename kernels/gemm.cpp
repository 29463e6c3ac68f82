#include "kernels/gemm.h"
#include "kernels/gemm_blocking.h"

#include <Eigen/Core>
#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <vector>

#ifdef SIRL_HAVE_XSMM
#include <libxsmm.h>
#endif
#include "kernels/aligned_vector.h"
#include "kernels/onednn_matmul.h"

namespace sirl {
namespace {

template <typename T>
using RowMat = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
template <typename T>
using MapC = Eigen::Map<const RowMat<T>>;

// C's columns are cut into fixed slices whatever the thread count (64 wide when N ≤ 256, e.g.
// the Grid nets' 128 units, so two threads still find work; 256 otherwise), and, for the libxsmm
// kernels, its rows into fixed blocks of kRowBlock: each block of C is one kernel call whose
// summation order depends on the block's shape only, so every result is bit-identical across
// thread counts; threads only decide who computes which slice.
constexpr int kRowBlock = 256;

template <typename Fn>
void for_column_slices(int N, int threads, Fn&& fn) {
  const int kSlice = gemm_column_slice(N);
  const int slices = (N + kSlice - 1) / kSlice;
  if (threads <= 1 || slices <= 1) {
    for (int p = 0; p < slices; ++p) fn(p * kSlice, std::min(kSlice, N - p * kSlice));
    return;
  }
#pragma omp parallel for num_threads(threads) schedule(static)
  for (int p = 0; p < slices; ++p) fn(p * kSlice, std::min(kSlice, N - p * kSlice));
}

// ---- Eigen: the generic path (any CPU; SIRL_KERNELS=generic forces it) ----

// Each writes C's columns [j0, j0+nj) at Cs with row stride ldc (Cs = C + j0, ldc = N in place).
template <typename T>
using SliceMap = Eigen::Map<RowMat<T>, 0, Eigen::OuterStride<>>;

template <typename T>
void eigen_nt(T* Cs, int ldc, const T* A, const T* B, int M, int N, int K, bool acc, int j0,
              int nj) {
  MapC<T> a(A, M, K), b(B, N, K);
  SliceMap<T> cs(Cs, M, nj, Eigen::OuterStride<>(ldc));
  if (acc)
    cs.noalias() += a * b.middleRows(j0, nj).transpose();
  else
    cs.noalias() = a * b.middleRows(j0, nj).transpose();
}
template <typename T>
void eigen_tn(T* Cs, int ldc, const T* A, const T* B, int M, int N, int K, bool acc, int j0,
              int nj) {
  MapC<T> a(A, K, M), b(B, K, N);
  SliceMap<T> cs(Cs, M, nj, Eigen::OuterStride<>(ldc));
  if (acc)
    cs.noalias() += a.transpose() * b.middleCols(j0, nj);
  else
    cs.noalias() = a.transpose() * b.middleCols(j0, nj);
}
template <typename T>
void eigen_nn(T* Cs, int ldc, const T* A, const T* B, int M, int N, int K, bool acc, int j0,
              int nj) {
  MapC<T> a(A, M, K), b(B, K, N);
  SliceMap<T> cs(Cs, M, nj, Eigen::OuterStride<>(ldc));
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
// libxsmm_smmdispatch builds a descriptor and looks it up in libxsmm's registry on every call:
// ~2 % of a GridRobot SIRL step, which makes ~30 calls. A per-thread direct-mapped memo of the
// kernels by their arguments skips that (the same kernel, so the same bits).
libxsmm_smmfunction xsmm_kernel(int m, int n, int k, int lda, int ldb, int ldc, bool trans_b,
                                bool acc) {
  struct Entry {
    int key[8];
    libxsmm_smmfunction kernel;
  };
  constexpr unsigned kSlots = 64;
  thread_local Entry memo[kSlots] = {};
  const int key[8] = {m, n, k, lda, ldb, ldc, trans_b, acc};
  unsigned h = 0;
  for (int v : key) h = h * 0x9E3779B1u + unsigned(v);
  Entry& e = memo[(h >> 8) % kSlots];
  if (e.kernel && std::memcmp(e.key, key, sizeof key) == 0) return e.kernel;
  const float alpha = 1, beta = acc ? 1 : 0;
  const int flags = trans_b ? LIBXSMM_GEMM_FLAG_TRANS_B : 0;
  const libxsmm_blasint bm = m, bn = n, bk = k, la = lda, lb = ldb, lc = ldc;
  const libxsmm_smmfunction kernel =
      libxsmm_smmdispatch(bm, bn, bk, &la, &lb, &lc, &alpha, &beta, &flags, nullptr);
  if (kernel) {
    std::memcpy(e.key, key, sizeof key);
    e.kernel = kernel;
  }
  return kernel;
}

// Cᶜ[m, n] (+)= op(Aᶜ)[m, k] · op(Bᶜ)[k, n], column-major, in blocks of kRowBlock columns of Cᶜ.
// Returns false when libxsmm has no kernel for the shape (the caller then uses Eigen).
bool xsmm_colmajor(const float* a, const float* b, float* c, int m, int n, int k, int lda, int ldb,
                   int ldc, bool trans_b, bool acc) {
  for (int n0 = 0; n0 < n; n0 += kRowBlock) {
    const libxsmm_smmfunction kernel =
        xsmm_kernel(m, std::min(kRowBlock, n - n0), k, lda, ldb, ldc, trans_b, acc);
    if (!kernel) return false;
    // op(Bᶜ)'s columns n0.. : column-major Bᶜ [k, n] starts at b + n0·ldb; transposed, Bᶜ is
    // [n, k] and its rows n0.. start at b + n0.
    kernel(a, b + (trans_b ? n0 : size_t(n0) * ldb), c + size_t(n0) * ldc);
  }
  return true;
}

thread_local AlignedVector<float> t_scratch;  // nt's transposed operand (and result)
#endif

// oneDNN's matmul primitive on one slice (kernels/onednn_matmul.h: row-major; 'T' reads that
// operand transposed), on the calling thread only, as every slice is. Whether a product goes
// there depends on its shape only. Two dimensions ≥ 512 and none below 32: with fewer rows (a TPA
// cell of M = 10 trains on 20), oneDNN packs a whole weight slice for little work. The matmul
// primitive, not dnnl_sgemm, whose slices of the JacoRobot forward product ran slower
// (bench/bench_gemm_candidates; the figures: docs/kernels.md, "The measurements behind the
// kernels' choices").
bool dnnl_big(int M, int N, int K) {
#ifdef SIRL_HAVE_DNNL
  return (M >= 512) + (N >= 512) + (K >= 512) >= 2 && std::min({M, N, K}) >= 32;
#else
  return false;
#endif
}
bool dnnl_slice(char ta, char tb, int M, int nj, int K, const float* A, int lda, const float* B,
                int ldb, bool acc, float* Cs, int ldc) {
  const bool at = ta == 'T', bt = tb == 'T';
  const MatmulShape s{M,   nj,  K,    at ? 1 : lda, at ? lda : 1, bt ? 1 : ldb, bt ? ldb : 1,
                      ldc, acc, false};
  return onednn_matmul(s, A, B, Cs);
}

template <typename T>
bool fast_nt(T*, int, const T*, const T*, int, int, int, bool, int, int) {
  return false;
}
template <typename T>
bool fast_tn(T*, int, const T*, const T*, int, int, int, bool, int, int) {
  return false;
}
template <typename T>
bool fast_nn(T*, int, const T*, const T*, int, int, int, bool, int, int) {
  return false;
}

#ifdef SIRL_HAVE_XSMM
// C[M,N] (+)= A[M,K]·B[N,K]ᵀ, columns [j0, j0+nj). libxsmm 1.17 cannot read its first operand
// transposed, so one operand is transposed first, whichever is smaller (a choice that depends on
// the shape only). Either way each element of C is the same FMA chain over k = 0..K−1, so both
// give the same bits:
//  (a) the slice of B:  Bt [nj, K] (column-major) = B[j0.., :], then Cᶜ [nj, M] = Bt · Aᶜ;
//  (b) A and the result: At [M, K] (column-major) = A, E [M, nj] = At · Bᶜ[:, j0..], C = Eᵀ.
// (b) moves M·(K + nj) floats instead of nj·K: far less for a training batch of 20–192 rows
// through a 1024 × 2037 JacoRobot layer, whose weights (a) copied at every forward pass.
template <>
bool fast_nt<float>(float* Cs, int ldc, const float* A, const float* B, int M, int N, int K,
                    bool acc, int j0, int nj) {
  if (dnnl_big(M, N, K))  // C[:, j0..] = A[M, K] · (B[j0.., K])ᵀ
    return dnnl_slice('N', 'T', M, nj, K, A, K, B + size_t(j0) * K, K, acc, Cs, ldc);
  AlignedVector<float>& scratch = t_scratch;
  if (M <= kRowBlock && size_t(M) * (K + nj) < size_t(nj) * K) {
    scratch.resize(size_t(M) * (K + nj));
    float* at = scratch.data();
    float* e = at + size_t(M) * K;
    libxsmm_otrans(at, A, sizeof(float), K, M, K, M);  // col-major [K, M] → [M, K]
    if (acc)
      for (int j = 0; j < nj; ++j)
        for (int i = 0; i < M; ++i) e[i + size_t(j) * M] = Cs[size_t(i) * ldc + j];
    if (!xsmm_colmajor(at, B + size_t(j0) * K, e, M, nj, K, M, K, M, false, acc)) return false;
    for (int i = 0; i < M; ++i)
      for (int j = 0; j < nj; ++j) Cs[size_t(i) * ldc + j] = e[i + size_t(j) * M];
    return true;
  }
  scratch.resize(size_t(K) * nj);
  libxsmm_otrans(scratch.data(), B + size_t(j0) * K, sizeof(float), K, nj, K, nj);
  return xsmm_colmajor(scratch.data(), A, Cs, nj, M, K, nj, K, ldc, false, acc);
}
// C[M,N] (+)= A[K,M]ᵀ·B[K,N]: Cᶜ = Bᶜ·(Aᶜ)ᵀ with Aᶜ = [M, K] column-major.
template <>
bool fast_tn<float>(float* Cs, int ldc, const float* A, const float* B, int M, int N, int K,
                    bool acc, int j0, int nj) {
  if (dnnl_big(M, N, K))  // C[:, j0..] = (A[K, M])ᵀ · B[K, j0..]
    return dnnl_slice('T', 'N', M, nj, K, A, M, B + j0, N, acc, Cs, ldc);
  return xsmm_colmajor(B + j0, A, Cs, nj, M, K, N, M, ldc, true, acc);
}
// C[M,N] (+)= A[M,K]·B[K,N]: Cᶜ = Bᶜ·Aᶜ.
template <>
bool fast_nn<float>(float* Cs, int ldc, const float* A, const float* B, int M, int N, int K,
                    bool acc, int j0, int nj) {
  if (dnnl_big(M, N, K))  // C[:, j0..] = A[M, K] · B[K, j0..]
    return dnnl_slice('N', 'N', M, nj, K, A, K, B + j0, N, acc, Cs, ldc);
  return xsmm_colmajor(B + j0, A, Cs, nj, M, K, N, K, ldc, false, acc);
}
#endif

}  // namespace

namespace {
// Defined with the row blocks below: one block of k of a big layer's ∂L/∂input, which
// matmul_nn_cols sums over the fused backward pass's blocks (gemm_nn_by_k_blocks).
void nn_k_block_slice(float* Cs, int ldc, const float* A, const float* B, int M, int N, int K,
                      bool acc, int k0, int kn, int j0, int nj);
}  // namespace

int gemm_column_slice(int N) {
  return N <= 256 ? 64 : 256;
}

template <typename T>
void matmul_nt_cols(T* Cs, int ldc, const T* A, const T* B, int M, int N, int K, bool accumulate,
                    int j0, int nj) {
  if (!(use_xsmm() && fast_nt<T>(Cs, ldc, A, B, M, N, K, accumulate, j0, nj)))
    eigen_nt<T>(Cs, ldc, A, B, M, N, K, accumulate, j0, nj);
}
template <typename T>
void matmul_tn_cols(T* Cs, int ldc, const T* A, const T* B, int M, int N, int K, bool accumulate,
                    int j0, int nj) {
  if (!(use_xsmm() && fast_tn<T>(Cs, ldc, A, B, M, N, K, accumulate, j0, nj)))
    eigen_tn<T>(Cs, ldc, A, B, M, N, K, accumulate, j0, nj);
}
template <typename T>
void matmul_nn_cols(T* Cs, int ldc, const T* A, const T* B, int M, int N, int K, bool accumulate,
                    int j0, int nj) {
  if constexpr (std::is_same_v<T, float>) {
    if (gemm_nn_by_k_blocks(M, N, K)) {  // summed over the fused pass's blocks of k (matmul_nn)
      const int kn = gemm_weight_row_block(K, N, M);
      for (int k0 = 0; k0 < K; k0 += kn)
        nn_k_block_slice(Cs, ldc, A, B, M, N, K, accumulate || k0 > 0, k0, std::min(kn, K - k0), j0,
                         nj);
      return;
    }
  }
  if (!(use_xsmm() && fast_nn<T>(Cs, ldc, A, B, M, N, K, accumulate, j0, nj)))
    eigen_nn<T>(Cs, ldc, A, B, M, N, K, accumulate, j0, nj);
}

// ---- products oneDNN serves, by blocks of C's rows ----
//
// oneDNN's matmul runs a dense operand set on its brgemm kernels and hands strided ones (a
// 256-column slice of C) to its sgemm, which can read JacoRobot's transposed first-layer weights
// (K = 2037) at half speed (docs/kernels.md). So the forward and weight-gradient
// products compute such a product in blocks of C's rows, each one call over all N columns, dense:
// one block up to 128 rows, two (multiples of 16, so two threads can share it) up to 512, blocks of
// 256 above. The blocks depend on the shape only, so the bits do too.

int gemm_row_block(int M, int N, int K) {
  if (!(use_xsmm() && dnnl_big(M, N, K))) return 0;
  return M <= 128 ? M : std::min(kRowBlock, ((M + 1) / 2 + 15) / 16 * 16);
}

// A layer of at least 256 Ki weights (1 MiB) no longer fits a core's share of L2 with its Adam
// moments: blocks of ~64 Ki weights. A layer of 4 Ki to 256 Ki weights (GridRobot's 128 × 128)
// fits; on one thread it goes by blocks of kRowBlock rows, the blocks libxsmm's calls cut the
// whole product into (xsmm_colmajor), so Adam runs over whole rows instead of 64-wide pieces of
// them (faster for the Grid heads and the unfrozen Grid TPA step: docs/kernels.md); with more
// threads, by column slices, which two threads share. Below 4 Ki, column slices.
constexpr size_t kBigLayer = size_t(1) << 18, kMidLayer = size_t(1) << 12;

int gemm_weight_row_block(int M, int N, int K, int threads) {
  if (const int block = gemm_row_block(M, N, K)) return block;
  if (!use_xsmm() || size_t(M) * N < kMidLayer) return 0;
  if (size_t(M) * N < kBigLayer) return threads <= 1 ? std::min(M, kRowBlock) : 0;
  return std::clamp((1 << 16) / N, 1, M);
}

namespace {
// A layer's weight gradient dW [M, N] (M units, N inputs, K batch rows) that libxsmm serves and
// the fused backward pass updates by blocks of ~64 Ki weights.
bool big_xsmm_layer(int M, int N, int K) {
  return use_xsmm() && !dnnl_big(M, N, K) && size_t(M) * N >= kBigLayer;
}

// Rows [i0, i0 + mi) of C = op(A) · op(B) into Cr (row stride N): oneDNN, or Eigen should
// oneDNN refuse the shape.
enum class Form { kNt, kTn };
void rows_of_product(Form op, float* Cr, const float* A, const float* B, int M, int N, int K,
                     bool acc, int i0, int mi) {
  using RowMatF = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  Eigen::Map<RowMatF> c(Cr, mi, N);
  if (op == Form::kNt) {  // C[M,N] = A[M,K]·B[N,K]ᵀ (the forward product)
    if (onednn_matmul({mi, N, K, K, 1, 1, K, N, acc, false}, A + size_t(i0) * K, B, Cr)) return;
    const auto prod = Eigen::Map<const RowMatF>(A, M, K).middleRows(i0, mi) *
                      Eigen::Map<const RowMatF>(B, N, K).transpose();
    acc ? void(c.noalias() += prod) : void(c.noalias() = prod);
  } else {  // C[M,N] = A[K,M]ᵀ·B[K,N]: op(A)'s rows i0.. have strides (1, M)
    if (onednn_matmul({mi, N, K, 1, M, N, 1, N, acc, false}, A + i0, B, Cr)) return;
    const auto prod = Eigen::Map<const RowMatF>(A, K, M).middleCols(i0, mi).transpose() *
                      Eigen::Map<const RowMatF>(B, K, N);
    acc ? void(c.noalias() += prod) : void(c.noalias() = prod);
  }
}

// A forward product of few rows (M ≤ 128: one row block, e.g. the VAE's and the preference
// trainings' batches of 32) in fixed blocks of kRowBlock columns, so that a task on several
// cores shares it: each block reads a dense band of W's rows (op(B)'s columns) and writes a dense
// [M, nb] buffer, copied into C's columns (a strided C would send oneDNN to its sgemm). The
// blocks depend on the shape only.
void nt_by_column_blocks(float* C, const float* A, const float* B, int M, int N, int K, bool acc,
                         int threads) {
  const int blocks = (N + kRowBlock - 1) / kRowBlock;
#pragma omp parallel for num_threads(threads) schedule(static) if (threads > 1)
  for (int b = 0; b < blocks; ++b) {
    const int j0 = b * kRowBlock, nb = std::min(kRowBlock, N - j0);
    thread_local AlignedVector<float> tmp;
    tmp.resize(size_t(M) * nb);
    // tmp[M, nb] = A · (W's rows j0..)ᵀ: the product of a dense [nb, K] band, whole.
    rows_of_product(Form::kNt, tmp.data(), A, B + size_t(j0) * K, M, nb, K, false, 0, M);
    for (int i = 0; i < M; ++i) {
      float* c = C + size_t(i) * N + j0;
      const float* t = tmp.data() + size_t(i) * nb;
      if (acc)
        for (int j = 0; j < nb; ++j) c[j] += t[j];
      else
        std::copy(t, t + nb, c);
    }
  }
}

// The whole product by row blocks when oneDNN serves it; false (nothing done) otherwise.
template <typename T>
bool by_row_blocks(Form op, T* C, const T* A, const T* B, int M, int N, int K, bool acc,
                   int threads) {
  if constexpr (std::is_same_v<T, float>) {
    const int block = gemm_row_block(M, N, K);
    if (!block) return false;
    if (op == Form::kNt && block == M && N >= 2 * kRowBlock) {
      nt_by_column_blocks(C, A, B, M, N, K, acc, threads);
      return true;
    }
    const int blocks = (M + block - 1) / block;
#pragma omp parallel for num_threads(threads) schedule(static) if (threads > 1 && blocks > 1)
    for (int b = 0; b < blocks; ++b)
      rows_of_product(op, C + size_t(b) * block * N, A, B, M, N, K, acc, b * block,
                      std::min(block, M - b * block));
    return true;
  } else {
    return false;
  }
}
}  // namespace

void matmul_tn_rows(float* Cr, const float* A, const float* B, int M, int N, int K, bool acc,
                    int i0, int mi) {
#ifdef SIRL_HAVE_XSMM
  // Where libxsmm serves the product: each column slice of the block as matmul_tn's slice would
  // compute it (Cᶜ = Bᶜ·(Aᶜ)ᵀ, the block's rows of C being columns i0.. of Cᶜ), so every element
  // is the same FMA chain over k = 0..K−1 and has the same bits.
  if (!dnnl_big(M, N, K) && use_xsmm()) {
    const int w = gemm_column_slice(N);
    bool done = true;
    for (int j0 = 0; j0 < N && done; j0 += w)
      done = xsmm_colmajor(B + j0, A + i0, Cr + j0, std::min(w, N - j0), mi, K, N, M, N, true, acc);
    if (done) return;
  }
#endif
  rows_of_product(Form::kTn, Cr, A, B, M, N, K, acc, i0, mi);
}

template <typename T>
void matmul_nt(T* C, const T* A, const T* B, int M, int N, int K, bool accumulate, int threads) {
  if (by_row_blocks<T>(Form::kNt, C, A, B, M, N, K, accumulate, threads)) return;
  for_column_slices(N, threads, [&](int j0, int nj) {
    matmul_nt_cols<T>(C + j0, N, A, B, M, N, K, accumulate, j0, nj);
  });
}

template <typename T>
void matmul_tn(T* C, const T* A, const T* B, int M, int N, int K, bool accumulate, int threads) {
  if (by_row_blocks<T>(Form::kTn, C, A, B, M, N, K, accumulate, threads)) return;
  if constexpr (std::is_same_v<T, float>) {
    // A big layer's weight gradient libxsmm serves: by the fused backward pass's blocks of weight
    // rows (matmul_tn_rows), so that both give the same bits by construction, whatever the
    // summation order of libxsmm's kernel for each block height.
    if (big_xsmm_layer(M, N, K)) {
      const int block = gemm_weight_row_block(M, N, K), blocks = (M + block - 1) / block;
#pragma omp parallel for num_threads(threads) schedule(static) if (threads > 1 && blocks > 1)
      for (int b = 0; b < blocks; ++b)
        matmul_tn_rows(C + size_t(b) * block * N, A, B, M, N, K, accumulate, b * block,
                       std::min(block, M - b * block));
      return;
    }
  }
  for_column_slices(N, threads, [&](int j0, int nj) {
    matmul_tn_cols<T>(C + j0, N, A, B, M, N, K, accumulate, j0, nj);
  });
}

namespace {
// Columns [j0, j0 + nj) of C (+)= A[:, k0..k0+kn) · B[k0..k0+kn, :] (A's row stride K), written
// at Cs with row stride ldc: one libxsmm call per kRowBlock rows (Cᶜ = Bᶜ·Aᶜ on the inner block:
// Bᶜ's columns k0.. are B's rows k0.., Aᶜ's rows k0.. start at A + k0), Eigen should libxsmm
// refuse it.
void nn_k_block_slice(float* Cs, int ldc, const float* A, const float* B, int M, int N, int K,
                      bool acc, int k0, int kn, int j0, int nj) {
#ifdef SIRL_HAVE_XSMM
  if (xsmm_colmajor(B + size_t(k0) * N + j0, A + k0, Cs, nj, M, kn, N, K, ldc, false, acc)) return;
#endif
  using RowMatF = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  SliceMap<float> c(Cs, M, nj, Eigen::OuterStride<>(ldc));
  const auto a = MapC<float>(A, M, K).middleCols(k0, kn);
  const auto b = Eigen::Map<const RowMatF>(B, K, N).block(k0, j0, kn, nj);
  acc ? void(c.noalias() += a * b) : void(c.noalias() = a * b);
}
}  // namespace

// ∂L/∂input stays in column slices: oneDNN's sgemm reads these operands untransposed at full
// speed (docs/kernels.md), and its dense path was no faster
// in A/B runs of the JacoRobot SIRL step and TPA cells. A big layer libxsmm serves sums each
// slice over the fused pass's blocks of the inner dimension, one after the other (as
// matmul_nn_k_block does): the same bits on any thread count and in either pass by construction.
// (libxsmm's kernels are not all one FMA chain over k: a 700-unit layer's whole product and its
// sum over blocks of 163 differed in 2–4 % of the elements.)
template <typename T>
void matmul_nn(T* C, const T* A, const T* B, int M, int N, int K, bool accumulate, int threads) {
  for_column_slices(N, threads, [&](int j0, int nj) {
    matmul_nn_cols<T>(C + j0, N, A, B, M, N, K, accumulate, j0, nj);
  });
}

// ∂L/∂input [M, N] = dY [M, K] · W [K, N] of a big layer libxsmm serves (K the layer's units):
// the layers the fused backward pass updates by blocks of weight rows.
bool gemm_nn_by_k_blocks(int M, int N, int K) {
  return big_xsmm_layer(K, N, M);
}

void matmul_nn_k_block(float* C, const float* A, const float* B, int M, int N, int K, bool acc,
                       int k0, int kn) {
  const int w = gemm_column_slice(N);
  for (int j0 = 0; j0 < N; j0 += w)
    nn_k_block_slice(C + j0, N, A, B, M, N, K, acc, k0, kn, j0, std::min(w, N - j0));
}

std::string libxsmm_target() {
#ifdef SIRL_HAVE_XSMM
  if (!use_xsmm()) return "";
  const char* arch = libxsmm_get_target_arch();
  return arch ? arch : "";
#else
  return "";
#endif
}

const char* gemm_backend() {
#ifdef SIRL_HAVE_DNNL
  return use_xsmm() ? "libxsmm+onednn" : "eigen";
#else
  return use_xsmm() ? "libxsmm" : "eigen";
#endif
}

#define SIRL_INSTANTIATE(T)                                                                    \
  template void matmul_nt<T>(T*, const T*, const T*, int, int, int, bool, int);                \
  template void matmul_tn<T>(T*, const T*, const T*, int, int, int, bool, int);                \
  template void matmul_nn<T>(T*, const T*, const T*, int, int, int, bool, int);                \
  template void matmul_nt_cols<T>(T*, int, const T*, const T*, int, int, int, bool, int, int); \
  template void matmul_tn_cols<T>(T*, int, const T*, const T*, int, int, int, bool, int, int); \
  template void matmul_nn_cols<T>(T*, int, const T*, const T*, int, int, int, bool, int, int);
SIRL_INSTANTIATE(float)
SIRL_INSTANTIATE(double)
#undef SIRL_INSTANTIATE

std::string libxsmm_version() {
#ifdef SIRL_HAVE_XSMM
  return LIBXSMM_VERSION;
#else
  return "not in this build";
#endif
}

std::string eigen_version() {
  return std::to_string(EIGEN_WORLD_VERSION) + "." + std::to_string(EIGEN_MAJOR_VERSION) + "." +
         std::to_string(EIGEN_MINOR_VERSION);
}
}  // namespace sirl
