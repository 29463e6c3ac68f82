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

// The parts of a product (kernels/product_plan.h: plan_product says which a product has; the
// rules are kernels/gemm_blocking.h's), each with the same bits as in the whole product:
// - a column slice [j0, j0 + nj) of C, written at Cs with row stride ldc (Cs = C + j0, ldc = N
//   gives the whole product's bits; a compact scratch, Cs[i·nj + j − j0] with ldc = nj, gives the
//   same values elsewhere);
template <typename T>
void matmul_nt_cols(T* Cs, int ldc, const T* A, const T* B, int M, int N, int K, bool accumulate,
                    int j0, int nj);
template <typename T>
void matmul_tn_cols(T* Cs, int ldc, const T* A, const T* B, int M, int N, int K, bool accumulate,
                    int j0, int nj);
template <typename T>
void matmul_nn_cols(T* Cs, int ldc, const T* A, const T* B, int M, int N, int K, bool accumulate,
                    int j0, int nj);
// - a block of the inner dimension of C[M,N] (+)= A[M, k0..k0+kn) · B[k0..k0+kn, N] (A's row
//   stride K): consecutive calls k0 = 0, kn, 2·kn, … with kn the plan's k_block, the first written
//   and the rest accumulated, give matmul_nn's bits;
void matmul_nn_k_block(float* C, const float* A, const float* B, int M, int N, int K,
                       bool accumulate, int k0, int kn);
// - rows [i0, i0 + mi) of C = A[K,M]ᵀ·B[K,N] alone into Cr [mi, N] (row stride N), blocks of the
//   plan's row_block: the same bits as that block of matmul_tn.
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
