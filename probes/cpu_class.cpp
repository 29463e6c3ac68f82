#include "probes/cpu_class.h"

#include <fstream>
#include <sstream>

#include "kernels/gemm.h"
#include "kernels/gemm_bf16.h"
#include "kernels/onednn_matmul.h"

namespace sirl {

bool avx512_in_use() {
  if (!__builtin_cpu_supports("avx512f")) return false;
  const std::string xsmm = libxsmm_target();
  const bool xsmm_wide = xsmm.empty() || xsmm == "skx" || xsmm == "clx" || xsmm == "cpx" ||
                         xsmm == "spr" || xsmm == "knl" || xsmm == "knm";
  return xsmm_wide && (onednn_isa().empty() || onednn_avx512());
}

std::string cpu_class() {
  std::ifstream in("/proc/cpuinfo");
  std::string line, vendor = "unknown", family = "?", model = "?", flags;
  while (std::getline(in, line)) {
    const auto colon = line.find(':');
    if (colon == std::string::npos) {
      if (!flags.empty()) break;  // the first processor's block is enough
      continue;
    }
    std::string key = line.substr(0, colon), value = line.substr(colon + 1);
    while (!key.empty() && (key.back() == ' ' || key.back() == '\t')) key.pop_back();
    if (!value.empty() && value.front() == ' ') value.erase(0, 1);
    if (key == "vendor_id") vendor = value;
    if (key == "cpu family") family = value;
    if (key == "model") model = value;
    if (key == "flags") flags = " " + value + " ";
  }
  const auto has = [&](const char* f) {
    return flags.find(" " + std::string(f) + " ") != std::string::npos;
  };
  std::string isa = has("avx512f") ? "avx512" : has("avx2") ? "avx2" : "sse";
  if (has("avx512_bf16")) isa += " bf16";
  // The libraries' own choice where they run, so a run told to stay at AVX2 is not filed with
  // the CPU's AVX-512 runs (its summation orders differ).
  if (isa.rfind("avx512", 0) == 0 && !avx512_in_use()) isa = "avx2";
  std::ostringstream s;
  s << vendor << " family " << family << " model " << model << ", " << isa << ", gemm "
    << gemm_backend();
  // The engine's own loops (losses, Adam, the linear probe's Eigen code) vectorise their
  // reductions by the compiled instruction set, so a native build's bits differ from the
  // portable one's on the same CPU: each is a class of its own.
  s << ", build " << SIRL_BUILD_ISA;
  return s.str();
}

std::string kernel_paths() {
  std::string s = std::string("build ") + SIRL_BUILD_ISA;
  if (const std::string x = libxsmm_target(); !x.empty()) s += "; libxsmm " + x;
  if (const std::string d = onednn_isa(); !d.empty()) s += "; onednn " + d;
  return s + "; gemm " + gemm_backend() + "; bf16 " + bf16_backend();
}

}  // namespace sirl
