// What a run's numbers depend on besides its inputs: the CPU class (vendor, family, model, the
// vector ISA used) and the GEMM backend. Same class, same bits; across classes the summation
// orders of the kernels differ, so digests are compared only within one class (bench/nightly).
#pragma once
#include <string>

namespace sirl {

// E.g. "AuthenticAMD family 25 model 17, avx512 bf16, gemm libxsmm+onednn, build x86-64-v3" (the
// portable build; "build native" for a -march=native one, whose bits differ from the portable
// build's on the same CPU; files before engine 0.9.0 have no "build": they were native builds).
// The vector ISA is the one
// the products use: the CPU's, unless the libraries were told to stay below it (LIBXSMM_TARGET,
// ONEDNN_MAX_CPU_ISA: a run limited to AVX2 on an AVX-512 CPU is of the class "avx2").
std::string cpu_class();

// Whether the products run on AVX-512 in this process: the CPU has it and neither libxsmm nor
// oneDNN was told to stay below it. The fp32 roof is measured with the same vector width.
bool avx512_in_use();

// Which code paths produce this process's numbers, e.g. "build x86-64-v3; libxsmm skx; onednn
// avx512_core_bf16; bf16 onednn-avx512_bf16": the instruction set the engine was compiled for,
// the ones libxsmm and oneDNN chose at run time, and the bf16 products' backend.
std::string kernel_paths();

}  // namespace sirl
