// The CPU class and kernel paths a run records: what its numbers depend on.
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <string>

#include "kernels/gemm.h"
#include "kernels/onednn_matmul.h"
#include "probes/cpu_class.h"

namespace sirl {
namespace {

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

TEST(CpuClass, NamesTheBuildAndTheLibrariesChoices) {
  const std::string k = kernel_paths();
  EXPECT_EQ(k.rfind("build ", 0), 0u) << k;
  EXPECT_TRUE(contains(k, "gemm " + std::string(gemm_backend()))) << k;
  EXPECT_TRUE(contains(k, "; bf16 ")) << k;
  if (!libxsmm_target().empty()) {
    EXPECT_TRUE(contains(k, "libxsmm " + libxsmm_target())) << k;
  }
}

// Run by the `avx2_kernels` ctest with LIBXSMM_TARGET=hsw and ONEDNN_MAX_CPU_ISA=AVX2: both
// libraries stay at AVX2 and the class says so, whatever the CPU offers. Without those variables
// it checks that a CPU with AVX-512 is of an avx512 class when the libraries use it.
TEST(CpuClass, FollowsTheLibrariesIsaLimits) {
  const char* dnnl = std::getenv("ONEDNN_MAX_CPU_ISA");
  const char* xsmm = std::getenv("LIBXSMM_TARGET");
  const std::string c = cpu_class(), k = kernel_paths();
  if (dnnl && std::strcmp(dnnl, "AVX2") == 0 && xsmm && std::strcmp(xsmm, "hsw") == 0) {
    EXPECT_TRUE(contains(c, ", avx2")) << c;
    if (!onednn_isa().empty()) {
      EXPECT_FALSE(onednn_avx512());
      EXPECT_TRUE(contains(k, "onednn avx2")) << k;
    }
    if (!libxsmm_target().empty()) {
      EXPECT_EQ(libxsmm_target(), "hsw");
    }
  } else if (onednn_avx512()) {
    EXPECT_TRUE(contains(c, ", avx512")) << c;
  }
}

}  // namespace
}  // namespace sirl
