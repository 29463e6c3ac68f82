#include "kernels/gemm_bf16.h"

#include <algorithm>
#include <bit>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "kernels/aligned_vector.h"
#include "kernels/gemm.h"
#include "kernels/gemm_blocking.h"
#include "kernels/onednn_matmul.h"

namespace sirl {
namespace {

// Below this in any dimension oneDNN's bf16 matmul lost to the fp32 kernels on the engine's
// shapes (bench/bench_gemm_candidates; the figures: docs/kernels.md).
constexpr int kBf16NativeMin = 32;

bool forced_off() {
  const char* k = std::getenv("SIRL_KERNELS");
  const char* b = std::getenv("SIRL_BF16");
  return (k && std::strcmp(k, "generic") == 0) || (b && std::strcmp(b, "emulate") == 0);
}

// ---- the emulation: widen to fp32 (exact) and run gemm.h's kernels ----
//
// Only the parts a slice reads are widened, into scratch laid out as the full operand, so the
// fp32 kernel sees the same shape, strides and slice as the emulation that rounds whole fp32
// copies (MlpShape::bf16_products before native kernels): the same bits.

float widen(uint16_t h) {
  return std::bit_cast<float>(uint32_t(h) << 16);
}
void widen(const uint16_t* x, float* y, size_t n) {
  for (size_t i = 0; i < n; ++i) y[i] = widen(x[i]);
}

struct WideScratch {
  std::vector<float> a, b;
};
WideScratch& wide_scratch() {
  thread_local WideScratch s;
  return s;
}

// A whole (or B whole: a weight gradient's block of rows needs all of it); B's rows [j0, j0 + nj)
// of [N, K] (nt) or its columns of [K, N] (tn, nn).
const float* widen_whole(std::vector<float>& s, const uint16_t* x, size_t n) {
  s.resize(n);
  widen(x, s.data(), n);
  return s.data();
}
const float* widen_a(const uint16_t* A, size_t n) {
  return widen_whole(wide_scratch().a, A, n);
}
const float* widen_b_rows(const uint16_t* B, int N, int K, int j0, int nj) {
  auto& s = wide_scratch().b;
  s.resize(size_t(N) * K);
  widen(B + size_t(j0) * K, s.data() + size_t(j0) * K, size_t(nj) * K);
  return s.data();
}
const float* widen_b_cols(const uint16_t* B, int K, int N, int j0, int nj) {
  auto& s = wide_scratch().b;
  s.resize(size_t(K) * N);
  for (int k = 0; k < K; ++k)
    widen(B + size_t(k) * N + j0, s.data() + size_t(k) * N + j0, size_t(nj));
  return s.data();
}

bool native_shape(int M, int nj, int K) {
  return bf16_native() && std::min({M, nj, K}) >= kBf16NativeMin;
}

// The native product of one column slice, C_s[M, nj] (+)= op(A) · op(B_s) with C_s at Cs, row
// stride s.ldc, computed as a dense [M, nj] result: oneDNN's AMX kernels (Sapphire Rapids) gave
// other bits for the same slice written at ldc = N than written densely (their blocking depends
// on the output's layout). A slice that is dense already (ldc = nj: the dW scratch) runs in place;
// any other goes through a buffer, M·nj floats copied against M·nj·K products (K ≥ kBf16NativeMin).
bool native_slice(MatmulShape s, const uint16_t* A, const uint16_t* Bs, float* Cs) {
  const long ldc = s.ldc;
  if (ldc == s.N) return onednn_matmul(s, A, Bs, Cs);
  thread_local AlignedVector<float> dense;
  dense.resize(size_t(s.M) * s.N);
  if (s.accumulate)
    for (int i = 0; i < s.M; ++i)
      std::memcpy(dense.data() + size_t(i) * s.N, Cs + i * ldc, sizeof(float) * s.N);
  s.ldc = s.N;
  if (!onednn_matmul(s, A, Bs, dense.data())) return false;
  for (int i = 0; i < s.M; ++i)
    std::memcpy(Cs + i * ldc, dense.data() + size_t(i) * s.N, sizeof(float) * s.N);
  return true;
}

template <typename Fn>
void for_slices(int N, int threads, Fn&& fn) {
  const int w = gemm_column_slice(N), slices = (N + w - 1) / w;
  if (threads <= 1 || slices <= 1) {
    for (int p = 0; p < slices; ++p) fn(p * w, std::min(w, N - p * w));
    return;
  }
#pragma omp parallel for num_threads(threads) schedule(static)
  for (int p = 0; p < slices; ++p) fn(p * w, std::min(w, N - p * w));
}

// The row block of a native weight gradient (gemm_bf16.h), 0 where it goes by column slices.
int native_row_block(int M, int N, int K) {
  return native_shape(M, N, K) ? gemm_row_block(M, N, K) : 0;
}

// The row blocks of a weight gradient that goes by them: in parallel (each block's bits are its
// own, so any thread count gives the same), into C [M, N] (row stride N).
void tn_by_row_blocks(int block, float* C, const uint16_t* A, const uint16_t* B, int M, int N,
                      int K, bool acc, int threads) {
  const int blocks = (M + block - 1) / block;
#pragma omp parallel for num_threads(threads) schedule(static) if (threads > 1 && blocks > 1)
  for (int b = 0; b < blocks; ++b)
    matmul_bf16_tn_rows(C + size_t(b) * block * N, A, B, M, N, K, acc, b * block,
                        std::min(block, M - b * block));
}

}  // namespace

bool bf16_native() {
  static const bool on = !forced_off() && onednn_native_bf16();
  return on;
}

const char* bf16_backend() {
  if (!bf16_native()) return "emulated";
  return onednn_amx_bf16() ? "onednn-amx_bf16" : "onednn-avx512_bf16";
}

void matmul_bf16_nt_cols(float* Cs, int ldc, const uint16_t* A, const uint16_t* B, int M, int N,
                         int K, bool acc, int j0, int nj) {
  // op(B) = (B[j0.., K])ᵀ: [K, nj] with strides (1, K)
  if (native_shape(M, nj, K) &&
      native_slice({M, nj, K, K, 1, 1, K, ldc, acc, true}, A, B + size_t(j0) * K, Cs))
    return;
  matmul_nt_cols<float>(Cs, ldc, widen_a(A, size_t(M) * K), widen_b_rows(B, N, K, j0, nj), M, N, K,
                        acc, j0, nj);
}

void matmul_bf16_tn_cols(float* Cs, int ldc, const uint16_t* A, const uint16_t* B, int M, int N,
                         int K, bool acc, int j0, int nj) {
  if (const int block = native_row_block(M, N, K)) {
    // A product that goes by row blocks: the slice of those blocks' result (every column of them
    // computed, into a dense buffer holding the slice's prior values where it accumulates).
    thread_local AlignedVector<float> whole;
    whole.resize(size_t(M) * N);
    for (int i = 0; acc && i < M; ++i)
      std::memcpy(whole.data() + size_t(i) * N + j0, Cs + size_t(i) * ldc, sizeof(float) * nj);
    tn_by_row_blocks(block, whole.data(), A, B, M, N, K, acc, 1);
    for (int i = 0; i < M; ++i)
      std::memcpy(Cs + size_t(i) * ldc, whole.data() + size_t(i) * N + j0, sizeof(float) * nj);
    return;
  }
  // op(A) = A[K, M]ᵀ: [M, K] with strides (1, M); op(B) = B[:, j0..]: [K, nj], strides (N, 1)
  if (native_shape(M, nj, K) && native_slice({M, nj, K, 1, M, N, 1, ldc, acc, true}, A, B + j0, Cs))
    return;
  matmul_tn_cols<float>(Cs, ldc, widen_a(A, size_t(K) * M), widen_b_cols(B, K, N, j0, nj), M, N, K,
                        acc, j0, nj);
}

void matmul_bf16_nn_cols(float* Cs, int ldc, const uint16_t* A, const uint16_t* B, int M, int N,
                         int K, bool acc, int j0, int nj) {
  if (native_shape(M, nj, K) && native_slice({M, nj, K, K, 1, N, 1, ldc, acc, true}, A, B + j0, Cs))
    return;
  matmul_nn_cols<float>(Cs, ldc, widen_a(A, size_t(M) * K), widen_b_cols(B, K, N, j0, nj), M, N, K,
                        acc, j0, nj);
}

int gemm_bf16_weight_row_block(int M, int N, int K, int threads) {
  return native_shape(M, N, K) ? native_row_block(M, N, K)
                               : gemm_weight_row_block(M, N, K, threads);
}

void matmul_bf16_tn_rows(float* Cr, const uint16_t* A, const uint16_t* B, int M, int N, int K,
                         bool acc, int i0, int mi) {
  // op(A)'s rows i0..: A[K, M]ᵀ from column i0, strides (1, M); B [K, N] whole; Cr dense [mi, N]
  if (native_shape(mi, N, K) && onednn_matmul({mi, N, K, 1, M, N, 1, N, acc, true}, A + i0, B, Cr))
    return;
  matmul_tn_rows(Cr, widen_a(A, size_t(K) * M), widen_whole(wide_scratch().b, B, size_t(K) * N), M,
                 N, K, acc, i0, mi);
}

void matmul_bf16_nt(float* C, const uint16_t* A, const uint16_t* B, int M, int N, int K, bool acc,
                    int threads) {
  for_slices(N, threads,
             [&](int j0, int nj) { matmul_bf16_nt_cols(C + j0, N, A, B, M, N, K, acc, j0, nj); });
}
void matmul_bf16_tn(float* C, const uint16_t* A, const uint16_t* B, int M, int N, int K, bool acc,
                    int threads) {
  if (const int block = native_row_block(M, N, K))
    return tn_by_row_blocks(block, C, A, B, M, N, K, acc, threads);
  for_slices(N, threads,
             [&](int j0, int nj) { matmul_bf16_tn_cols(C + j0, N, A, B, M, N, K, acc, j0, nj); });
}
void matmul_bf16_nn(float* C, const uint16_t* A, const uint16_t* B, int M, int N, int K, bool acc,
                    int threads) {
  for_slices(N, threads,
             [&](int j0, int nj) { matmul_bf16_nn_cols(C + j0, N, A, B, M, N, K, acc, j0, nj); });
}

}  // namespace sirl
