// Row-major matrix products, the only GEMM the MLP kernels call. float runs libxsmm's JIT
// kernels for this CPU when the build has libxsmm (Debian libxsmm-dev), double and the generic
// path Eigen's GEMM; SIRL_KERNELS=generic in the environment forces Eigen (any CPU, and the
// path CI also tests). All matrices are dense, row-major, contiguous. C is computed in fixed
// slices; `threads` > 1 spreads the slices over OpenMP threads, and the result is bit-identical
// for any thread count (not across backends or CPU classes: their summation orders differ).
#pragma once
#include <string>

namespace sirl {

// C[M,N] (+)= A[M,K] · B[N,K]ᵀ      (forward:   Y = X Wᵀ)
template <typename T>
void matmul_nt(T* C, const T* A, const T* B, int M, int N, int K, bool accumulate, int threads = 1);

// C[M,N] (+)= A[K,M]ᵀ · B[K,N]      (weight grad: dW = dYᵀ X)
template <typename T>
void matmul_tn(T* C, const T* A, const T* B, int M, int N, int K, bool accumulate, int threads = 1);

// C[M,N] (+)= A[M,K] · B[K,N]       (input grad:  dX = dY W)
template <typename T>
void matmul_nn(T* C, const T* A, const T* B, int M, int N, int K, bool accumulate, int threads = 1);

// Every product above cuts C's N columns into fixed slices [j0, j0 + nj), j0 = 0, w, 2w, …, with
// w = gemm_column_slice(N), whatever the thread count. The *_cols forms compute one such slice and
// write it at Cs with row stride ldc (Cs = C + j0, ldc = N gives the whole product's bits; a
// compact scratch, Cs[i·nj + j − j0] with ldc = nj, gives the same values elsewhere). The fused
// backward pass (mlp_backward_adam) uses them to finish a slice of the weights at a time.
int gemm_column_slice(int N);
template <typename T>
void matmul_nt_cols(T* Cs, int ldc, const T* A, const T* B, int M, int N, int K, bool accumulate,
                    int j0, int nj);
template <typename T>
void matmul_tn_cols(T* Cs, int ldc, const T* A, const T* B, int M, int N, int K, bool accumulate,
                    int j0, int nj);
template <typename T>
void matmul_nn_cols(T* Cs, int ldc, const T* A, const T* B, int M, int N, int K, bool accumulate,
                    int j0, int nj);

// A float product oneDNN serves (two dimensions ≥ 512, none below 32) runs on its dense kernels
// in blocks of C's rows, all N columns at once: gemm_row_block(M, N, K) is the block height (fixed
// by the shape), 0 for a product that goes by column slices. matmul_nt and matmul_tn do so block
// by block (matmul_nn keeps column slices), and matmul_tn does so for a big layer libxsmm serves
// too (gemm_weight_row_block). matmul_tn_rows computes rows [i0, i0 + mi) of C = A[K,M]ᵀ·B[K,N]
// alone into Cr [mi, N] (row stride N), the same bits as that block of matmul_tn: the fused
// backward pass updates the weights a block of rows at a time.
int gemm_row_block(int M, int N, int K);
// The fused backward pass's block of weight rows for a weight gradient dW[M,N] = A[K,M]ᵀ·B[K,N]
// (M units, N inputs, K batch rows): gemm_row_block's where oneDNN serves the product; for a big
// layer libxsmm serves (≥ 256 Ki weights, few batch rows: a TPA cell of M = 10 trains on 20),
// blocks of ~64 Ki weights, so that a block's weights, Adam moments and gradient stay in cache and
// are read contiguously (column slices of a 1024 × 2037 layer read its rows 1 KiB at a time, and
// Adam ran at half speed on them); for a layer of 4 Ki to 256 Ki weights on one thread, blocks of
// 256 rows (Adam over whole rows); 0 where it goes by column slices. matmul_tn computes a big
// layer's gradient by these blocks too, so both have the same bits.
int gemm_weight_row_block(int M, int N, int K, int threads = 1);
// C[M,N] (+)= A[M, k0..k0+kn) · B[k0..k0+kn, N] (A's row stride K): one block of matmul_nn's inner
// dimension. Where gemm_nn_by_k_blocks(M, N, K) (∂L/∂input of a big layer libxsmm serves),
// matmul_nn itself sums over the blocks kn = gemm_weight_row_block(K, N, M), one after the other,
// so consecutive calls k0 = 0, kn, 2·kn, …, the first written and the rest accumulated, give
// matmul_nn's bits by construction. The fused backward pass computes ∂L/∂input so while it
// updates the weights block by block, reading each block once.
bool gemm_nn_by_k_blocks(int M, int N, int K);
void matmul_nn_k_block(float* C, const float* A, const float* B, int M, int N, int K,
                       bool accumulate, int k0, int kn);
void matmul_tn_rows(float* Cr, const float* A, const float* B, int M, int N, int K, bool accumulate,
                    int i0, int mi);

// "libxsmm+onednn", "libxsmm" or "eigen": what float products run on in this process.
const char* gemm_backend();

// The instruction set libxsmm generates its kernels for in this process ("skx", "hsw", …: its
// target architecture, the CPU's best unless LIBXSMM_TARGET lowers it); "" without libxsmm.
std::string libxsmm_target();

// Versions of the libraries behind the products, as this build links them (provenance).
std::string libxsmm_version();
std::string eigen_version();
}  // namespace sirl
