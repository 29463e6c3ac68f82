// The loops that measure this CPU's compute peaks: probes/roofline.cpp runs them briefly in
// process (the roofs `sirl run` records), bench/bench_roofline.cpp at length. Each runs `iters`
// rounds of independent accumulator chains, more than latency × pipes, so the unit never waits,
// and returns a value that depends on every chain (so no compiler drops the work). The instruction
// set is chosen at run time: call a loop only where its check says the CPU has it.
#pragma once
#include <cstdint>

namespace sirl {

// vfmadd231ps on zmm: 16 chains × 16 lanes × 2 FLOP per round (needs AVX-512F).
float fma_loop_avx512(int64_t iters, float seed);
// vfmadd231ps on ymm: 12 chains × 8 lanes × 2 FLOP per round (needs AVX2 + FMA). AVX2 has 16 ymm
// registers: 16 accumulators and the two operands would spill (and fall well short of oneDNN's
// sgemm: docs/kernels.md); 12 chains still cover latency × pipes.
float fma_loop_avx2(int64_t iters, float seed);
double fma_loop_flops(bool avx512, int64_t iters);

// vdpbf16ps on zmm: 16 chains × 16 fp32 lanes × (2 bf16 products + their sums) = 4 FLOP per lane
// per round (needs AVX512_BF16).
bool has_avx512_bf16();
float dpbf16_loop(int64_t iters, float seed);
double dpbf16_loop_flops(int64_t iters);

// AMX tdpbf16ps: 4 chains, each a 16 × 16 fp32 tile += (16 × 32 bf16) · (32 × 16 bf16), 16384
// FLOP per instruction; `iters` counts rounds of 16 dot products per lane as the loops above
// (iters / 16 tile rounds). amx_bf16_usable() asks Linux for the tile data state (once per
// process; a thread inherits it): false where the CPU or the kernel offers no AMX-BF16.
bool amx_bf16_usable();
float amx_bf16_loop(int64_t iters, float seed);
double amx_bf16_loop_flops(int64_t iters);

}  // namespace sirl
