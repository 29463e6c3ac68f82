// bfloat16 rounding for the bf16 precision mode (MlpShape::bf16_products): a matrix product of
// bf16 operands with fp32 accumulation, as AVX512-BF16's vdpbf16ps computes it. A bf16 value is
// an fp32 value whose low 16 mantissa bits are zero, so the products of two of them are exact in
// fp32: rounding both operands to bf16 and running the fp32 GEMM gives bf16 products with fp32
// accumulation on any CPU (only the summation order, and vdpbf16ps's flushing of denormals,
// differ from the native instruction).
#pragma once
#include <cstddef>
#include <cstdint>

namespace sirl {

// x rounded to the nearest bfloat16 (ties to even), returned as a float. NaN stays NaN (quiet),
// ±inf stays ±inf, and a finite value beyond bf16's largest rounds to ±inf as IEEE rounding does.
float round_to_bf16(float x);

// y[i] = round_to_bf16(x[i]) for i < n (y may equal x).
void round_to_bf16(const float* x, float* y, size_t n);

// The same rounding stored as bf16 bit patterns (the upper 16 bits of round_to_bf16(x[i])), the
// operand format of vdpbf16ps and of oneDNN's bf16 matmul.
void to_bf16_bits(const float* x, uint16_t* y, size_t n);

}  // namespace sirl
