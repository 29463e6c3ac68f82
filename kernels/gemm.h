// Row-major matrix products, the only place the MLP kernels touch Eigen's GEMM.
// All matrices are dense, row-major, contiguous. C is computed in fixed 256-column slices;
// `threads` > 1 spreads the slices over OpenMP threads, and the result is bit-identical for
// any thread count.
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

}  // namespace sirl
