#include "kernels/cpu_class.h"

#include <fstream>
#include <sstream>

#include "kernels/gemm.h"

namespace sirl {

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
  std::ostringstream s;
  s << vendor << " family " << family << " model " << model << ", " << isa << ", gemm "
    << gemm_backend();
  return s.str();
}

}  // namespace sirl
