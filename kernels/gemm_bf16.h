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

// The fused backward pass's block of weight rows for a weight gradient dW[M,N] = A[K,M]ᵀ·B[K,N]
// (M units, N inputs, K batch rows), 0 where it goes by column slices. A native product that
// gemm.h's fp32 kernels compute by blocks of rows (gemm_row_block: two dimensions ≥ 512, such as
// JacoRobot's 1024-wide layers at 32 rows or more) goes by the same blocks, each all N columns
// at once, dense, and matmul_bf16_tn does so too, so the height is fixed by the shape. An
// emulated product takes the fp32 kernel's own blocks (gemm_weight_row_block), whose bits are
// the whole product's. matmul_bf16_tn_rows computes rows [i0, i0 + mi) alone into Cr [mi, N]
// (row stride N), the same bits as that block of matmul_bf16_tn. With whole rows Adam reads a
// layer's weights and moments contiguously: by 256-wide column slices it read a 1024 × 2037
// layer 1 KiB a row at a time, and took 44 % of a JacoRobot unfrozen TPA step in bf16.
int gemm_bf16_weight_row_block(int M, int N, int K, int threads = 1);
void matmul_bf16_tn_rows(float* Cr, const uint16_t* A, const uint16_t* B, int M, int N, int K,
                         bool accumulate, int i0, int mi);

// One column slice [j0, j0 + nj) of the products above, written at Cs with row stride ldc. For a
// weight gradient that goes by row blocks the slice is cut from those blocks' whole result (the
// same bits, at the cost of the whole product: no caller slices such a product).
void matmul_bf16_nt_cols(float* Cs, int ldc, const uint16_t* A, const uint16_t* B, int M, int N,
                         int K, bool accumulate, int j0, int nj);
void matmul_bf16_tn_cols(float* Cs, int ldc, const uint16_t* A, const uint16_t* B, int M, int N,
                         int K, bool accumulate, int j0, int nj);
void matmul_bf16_nn_cols(float* Cs, int ldc, const uint16_t* A, const uint16_t* B, int M, int N,
                         int K, bool accumulate, int j0, int nj);

}  // namespace sirl
