#include "kernels/roofline.h"

#include <immintrin.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <vector>

namespace sirl {

namespace {

constexpr int kChains = 16;  // more than latency × pipes: the FMA units never wait
// AVX2 has 16 ymm registers: 16 accumulators and the two operands would spill to the stack
// (measured on a Zen 3: 53 GFLOP/s a core, where oneDNN\'s sgemm reached 80). 12 chains still
// cover latency × pipes.
constexpr int kChainsYmm = 12;

// 16 lanes × 2 FLOP per instruction; returns a value so the loop is not optimised away.
__attribute__((target("avx512f"))) float fma_avx512(int64_t iters) {
  __m512 acc[kChains];
  for (int c = 0; c < kChains; ++c) acc[c] = _mm512_set1_ps(float(c));
  const __m512 a = _mm512_set1_ps(0.999f), b = _mm512_set1_ps(1e-3f);
  for (int64_t i = 0; i < iters; ++i)
    for (int c = 0; c < kChains; ++c) acc[c] = _mm512_fmadd_ps(acc[c], a, b);
  alignas(64) float x[16];
  __m512 s = acc[0];
  for (int c = 1; c < kChains; ++c) s = _mm512_add_ps(s, acc[c]);
  _mm512_store_ps(x, s);
  return x[0];
}

// 8 lanes × 2 FLOP per instruction.
__attribute__((target("avx2,fma"))) float fma_avx2(int64_t iters) {
  __m256 acc[kChainsYmm];
  for (int c = 0; c < kChainsYmm; ++c) acc[c] = _mm256_set1_ps(float(c));
  const __m256 a = _mm256_set1_ps(0.999f), b = _mm256_set1_ps(1e-3f);
  for (int64_t i = 0; i < iters; ++i)
    for (int c = 0; c < kChainsYmm; ++c) acc[c] = _mm256_fmadd_ps(acc[c], a, b);
  alignas(32) float x[8];
  __m256 s = acc[0];
  for (int c = 1; c < kChainsYmm; ++c) s = _mm256_add_ps(s, acc[c]);
  _mm256_store_ps(x, s);
  return x[0];
}

double measure() {
  const bool wide = __builtin_cpu_supports("avx512f");
  if (!wide && !__builtin_cpu_supports("fma")) return 0;  // no FMA: no roof to report
  const int64_t iters = 1 << 16;                          // ~0.3 ms a probe
  const double flops = double(iters) * (wide ? kChains * 16 : kChainsYmm * 8) * 2;
  double best = 0;
  volatile float sink = 0;
  for (int probe = 0; probe < 5; ++probe) {
    const auto t0 = std::chrono::steady_clock::now();
    sink = sink + (wide ? fma_avx512(iters) : fma_avx2(iters));
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (s > 0) best = std::max(best, flops / s * 1e-9);
  }
  return best;
}

}  // namespace

double fp32_roof_gflops_per_core() {
  static const double roof = measure();
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
