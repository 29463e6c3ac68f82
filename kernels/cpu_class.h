// What a run's numbers depend on besides its inputs: the CPU class (vendor, family, model, the
// vector ISA used) and the GEMM backend. Same class, same bits; across classes the summation
// orders of the kernels differ, so digests are compared only within one class (bench/nightly).
#pragma once
#include <string>

namespace sirl {

// E.g. "AuthenticAMD family 25 model 17, avx512 bf16, gemm libxsmm".
std::string cpu_class();

}  // namespace sirl
