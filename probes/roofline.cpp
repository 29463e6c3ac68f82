#include "probes/roofline.h"

#include "probes/cpu_class.h"

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "kernels/gemm_bf16.h"
#include "probes/peak_loops.h"

namespace sirl {

namespace {

// Best GFLOP/s of five short runs of a peak loop (each a fixed number of iterations).
template <typename Loop>
double best_of_probes(Loop&& loop, double flops) {
  double best = 0;
  volatile float sink = 0;
  for (int probe = 0; probe < 5; ++probe) {
    const auto t0 = std::chrono::steady_clock::now();
    sink = sink + loop();
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (s > 0) best = std::max(best, flops / s * 1e-9);
  }
  return best;
}

constexpr int64_t kIters = 1 << 16;

double measure_fp32() {
  const bool wide = avx512_in_use();                      // the width the products run at
  if (!wide && !__builtin_cpu_supports("fma")) return 0;  // no FMA: no roof to report
  return best_of_probes(
      [&] { return wide ? fma_loop_avx512(kIters, 1.f) : fma_loop_avx2(kIters, 1.f); },
      fma_loop_flops(wide, kIters));
}

// The unit bf16_backend() multiplies on: AMX tiles, else vdpbf16ps, else none (emulated).
double measure_bf16() {
  const std::string backend = bf16_backend();
  if (backend == "onednn-amx_bf16" && amx_bf16_usable())
    return best_of_probes([] { return amx_bf16_loop(kIters * 16, 1.f); },
                          amx_bf16_loop_flops(kIters * 16));
  if (backend == "onednn-avx512_bf16" && has_avx512_bf16())
    return best_of_probes([] { return dpbf16_loop(kIters, 1.f); }, dpbf16_loop_flops(kIters));
  return 0;
}

}  // namespace

double fp32_roof_gflops_per_core() {
  static const double roof = measure_fp32();
  return roof;
}

double bf16_roof_gflops_per_core() {
  static const double roof = measure_bf16();
  return roof;
}

namespace {
double measure_triad() {
  const size_t n = size_t(8) << 20;  // 8 Mi floats = 32 MiB per array
  std::vector<float> a(n), b(n, 1.f), c(n, 2.f);
  const float s = 0.5f;
  double best = 0;
  for (int pass = 0; pass < 4; ++pass) {
    const auto t0 = std::chrono::steady_clock::now();
    float* __restrict pa = a.data();
    const float* __restrict pb = b.data();
    const float* __restrict pc = c.data();
#pragma omp simd
    for (size_t i = 0; i < n; ++i) pa[i] = pb[i] + s * pc[i];
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    volatile float sink = pa[n / 2];
    (void)sink;
    if (pass > 0 && t > 0) best = std::max(best, 12.0 * double(n) / t * 1e-9);
  }
  return best;
}
}  // namespace

double stream_gbs_per_core() {
  static const double gbs = measure_triad();
  return gbs;
}

}  // namespace sirl
