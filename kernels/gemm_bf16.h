// Matrix products of precision "bf16" (MlpShape::bf16_products): operands are bf16 bit patterns
// (kernels/bf16.h: to_bf16_bits), products are exact in fp32 and accumulate in fp32, the result
// is fp32. Shapes, slicing and the *_cols convention are gemm.h's.
//
// Where the CPU has AVX512-BF16 and the build has oneDNN, a product whose dimensions are all
// ≥ kBf16NativeMin runs on oneDNN's bf16 matmul: on AMX tiles where the CPU has them (Sapphire
// Rapids and later), else vdpbf16ps (twice the fp32 FMA rate on Zen 4/5, half of it on Sapphire
// Rapids). Its bits depend on the CPU's kernel, as fp32's do on the GEMM backend. Every other
// product widens its operands to fp32 (exactly) and runs gemm.h's fp32 kernels: the emulation
// that gives the same values up to summation order on any CPU. SIRL_BF16=emulate (or
// SIRL_KERNELS=generic) forces the emulation. Either way the bits depend on the shape only,
// never on the thread count.
#pragma once
#include <cstdint>

namespace sirl {

// True when products large enough run natively (AVX512-BF16 + oneDNN, not forced off).
bool bf16_native();
// "onednn-amx_bf16" (AMX tiles), "onednn-avx512_bf16" (vdpbf16ps) or "emulated": recorded with
// the CPU class.
const char* bf16_backend();

// C[M,N] (+)= A[M,K] · B[N,K]ᵀ
void matmul_bf16_nt(float* C, const uint16_t* A, const uint16_t* B, int M, int N, int K,
                    bool accumulate, int threads = 1);
// C[M,N] (+)= A[K,M]ᵀ · B[K,N]
void matmul_bf16_tn(float* C, const uint16_t* A, const uint16_t* B, int M, int N, int K,
                    bool accumulate, int threads = 1);
// C[M,N] (+)= A[M,K] · B[K,N]
void matmul_bf16_nn(float* C, const uint16_t* A, const uint16_t* B, int M, int N, int K,
                    bool accumulate, int threads = 1);

// One column slice [j0, j0 + nj) of the products above, written at Cs with row stride ldc.
void matmul_bf16_nt_cols(float* Cs, int ldc, const uint16_t* A, const uint16_t* B, int M, int N,
                         int K, bool accumulate, int j0, int nj);
void matmul_bf16_tn_cols(float* Cs, int ldc, const uint16_t* A, const uint16_t* B, int M, int N,
                         int K, bool accumulate, int j0, int nj);
void matmul_bf16_nn_cols(float* Cs, int ldc, const uint16_t* A, const uint16_t* B, int M, int N,
                         int K, bool accumulate, int j0, int nj);

}  // namespace sirl
