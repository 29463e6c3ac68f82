// oneDNN's matmul primitive (Debian libdnnl-dev) for the products gemm.h and gemm_bf16.h send it:
// one primitive per shape, created once per thread and cached, run on the calling thread only.
// With one thread oneDNN's blocking (and any split of K) is fixed by the shape, so the bits are
// too. Without oneDNN in the build every call returns false and the caller computes the product.
#pragma once
#include <cstdint>
#include <string>

namespace sirl {

// C[M, N] (+)= op(A)[M, K] · op(B)[K, N], fp32 result. Strides are in elements: op(A)[i, k] is
// A[i·a_rs + k·a_cs], op(B)[k, j] is B[k·b_rs + j·b_cs], C[i, j] is C[i·ldc + j]. Operands are
// fp32, or bf16 bit patterns (kernels/bf16.h) when bf16 (vdpbf16ps on AVX512-BF16; fp32
// accumulation either way).
struct MatmulShape {
  int M, N, K;
  long a_rs, a_cs, b_rs, b_cs, ldc;
  bool accumulate;
  bool bf16;
};

// False when the build has no oneDNN or oneDNN refuses the shape (the caller then falls back).
bool onednn_matmul(const MatmulShape& shape, const void* A, const void* B, float* C);

// Whether oneDNN runs bf16 products natively on this CPU (AVX512-BF16 or better).
bool onednn_native_bf16();
// Whether those products run on AMX tiles (Sapphire Rapids and later: `tdpbf16ps`).
bool onednn_amx_bf16();

// The instruction set oneDNN's kernels use in this process: the CPU's best unless
// ONEDNN_MAX_CPU_ISA lowers it ("avx512_core_bf16", "avx2", …; "" without oneDNN).
std::string onednn_isa();
// Whether that instruction set includes AVX-512 (oneDNN's avx512_core).
bool onednn_avx512();

// oneDNN's version at run time (major.minor.patch), for provenance.
std::string onednn_version();
}  // namespace sirl
