// Row-major matrix products, the only GEMM the MLP kernels call. float runs libxsmm's JIT
// kernels for this CPU when the build has libxsmm (Debian libxsmm-dev), double and the generic
// path Eigen's GEMM; SIRL_KERNELS=generic in the environment forces Eigen (any CPU, and the
// path CI also tests). All matrices are dense, row-major, contiguous. C is computed in fixed
// slices; `threads` > 1 spreads the slices over OpenMP threads, and the result is bit-identical
// for any thread count (not across backends or CPU classes: their summation orders differ).
#pragma once

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

// "libxsmm" or "eigen": what float products run on in this process.
const char* gemm_backend();

}  // namespace sirl
