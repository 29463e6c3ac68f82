// This CPU's roofline: the peak a kernel could reach, measured, so every kernel benchmark and
// task kind can report its share of it.
//   BM_PeakFp32Fma     16 independent chains of `vfmadd231ps` (zmm; ymm without AVX-512):
//                      2 FLOP per lane per instruction
//   BM_PeakBf16Dot     16 independent chains of `vdpbf16ps` (zmm): per fp32 lane, 2 bf16
//                      products summed into it, 4 FLOP per lane per instruction
//   BM_PeakAmxBf16     4 independent chains of `tdpbf16ps` on AMX tiles (Sapphire Rapids and
//                      later): each a 16 × 16 fp32 tile += 16 × 32 bf16 · 32 × 16 bf16, 16384
//                      FLOP per instruction. Where the CPU has AMX, this is its bf16 roof, and
//                      oneDNN's bf16 matmul runs on it.
//   BM_StreamTriad     a[i] = b[i] + s * c[i] over 3 × 64 MiB (far beyond the caches);
//                      bytes counted as STREAM counts them (2 reads + 1 write, 12 per element)
// Each runs on 1 thread and on every core (->Threads): the per-core and the machine roof (with
// threads, the counter is the machine's total: Google Benchmark sums the threads' rates, each
// over the shared wall time, so kAvgThreads undoes the double count).
// The instruction set is chosen at run time (__builtin_cpu_supports), like the engine's kernels.
#include <benchmark/benchmark.h>
#include <immintrin.h>

#include <cpuid.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cstdint>
#include <thread>
#include <vector>

namespace {

constexpr int kChains = 16;  // > latency (4) × pipes (2): the FMA units never wait
// AVX2 has 16 ymm registers: 16 accumulators and the two operands would spill to the stack
// (measured on a Zen 3: 53 GFLOP/s a core, where oneDNN\'s sgemm reached 80). 12 chains still
// cover latency × pipes.
constexpr int kChainsYmm = 12;
constexpr int64_t kIters = 1 << 16;  // per benchmark iteration

// The lanes' sum (GCC 12's _mm512_reduce_add_ps trips -Wuninitialized in its own header).
__attribute__((target("avx512f"))) float lane_sum(__m512 v) {
  alignas(64) float x[16];
  _mm512_store_ps(x, v);
  float t = 0;
  for (float f : x) t += f;
  return t;
}

__attribute__((target("avx512f"))) float fma_loop_avx512(float seed) {
  __m512 acc[kChains];
  for (int c = 0; c < kChains; ++c) acc[c] = _mm512_set1_ps(seed + float(c));
  const __m512 a = _mm512_set1_ps(0.999f), b = _mm512_set1_ps(1e-3f);
  for (int64_t i = 0; i < kIters; ++i)
    for (int c = 0; c < kChains; ++c) acc[c] = _mm512_fmadd_ps(acc[c], a, b);
  __m512 s = acc[0];
  for (int c = 1; c < kChains; ++c) s = _mm512_add_ps(s, acc[c]);
  return lane_sum(s);
}

__attribute__((target("avx2,fma"))) float fma_loop_avx2(float seed) {
  __m256 acc[kChainsYmm];
  for (int c = 0; c < kChainsYmm; ++c) acc[c] = _mm256_set1_ps(seed + float(c));
  const __m256 a = _mm256_set1_ps(0.999f), b = _mm256_set1_ps(1e-3f);
  for (int64_t i = 0; i < kIters; ++i)
    for (int c = 0; c < kChainsYmm; ++c) acc[c] = _mm256_fmadd_ps(acc[c], a, b);
  __m256 s = acc[0];
  for (int c = 1; c < kChainsYmm; ++c) s = _mm256_add_ps(s, acc[c]);
  alignas(32) float v[8];
  _mm256_store_ps(v, s);
  float t = 0;
  for (float x : v) t += x;
  return t;
}

__attribute__((target("avx512f,avx512bf16"))) float bf16_loop(float seed) {
  __m512 acc[kChains];
  for (int c = 0; c < kChains; ++c) acc[c] = _mm512_set1_ps(seed + float(c));
  const __m512bh a = _mm512_cvtne2ps_pbh(_mm512_set1_ps(0.5f), _mm512_set1_ps(0.25f));
  const __m512bh b = _mm512_cvtne2ps_pbh(_mm512_set1_ps(1e-3f), _mm512_set1_ps(2e-3f));
  for (int64_t i = 0; i < kIters; ++i)
    for (int c = 0; c < kChains; ++c) acc[c] = _mm512_dpbf16_ps(acc[c], a, b);
  __m512 s = acc[0];
  for (int c = 1; c < kChains; ++c) s = _mm512_add_ps(s, acc[c]);
  return lane_sum(s);
}

// CPUID.(7,0):EDX bit 22 AMX-BF16, bit 24 AMX-TILE; Linux grants a process the tile data
// state only on request (arch_prctl ARCH_REQ_XCOMP_PERM for XTILEDATA, feature 18).
bool has_amx_bf16() {
  unsigned a, b, c, d;
  if (!__get_cpuid_count(7, 0, &a, &b, &c, &d)) return false;
  if (!((d >> 22) & 1) || !((d >> 24) & 1)) return false;
  constexpr long kReqXcompPerm = 0x1023, kXtiledata = 18;
  return syscall(SYS_arch_prctl, kReqXcompPerm, kXtiledata) == 0;
}

// Palette 1: tiles 0-3 the 16 × 16 fp32 accumulators, 4-5 the A tiles (16 rows × 32 bf16),
// 6-7 the B tiles (16 rows of 32 bf16 pairs' VNNI layout); 64 bytes per row each.
struct alignas(64) TileConfig {
  uint8_t palette = 1, start_row = 0, reserved[14] = {};
  uint16_t colsb[16] = {};
  uint8_t rows[16] = {};
};

__attribute__((target("amx-tile,amx-bf16"))) float amx_loop(float seed) {
  TileConfig cfg;
  for (int t = 0; t < 8; ++t) cfg.colsb[t] = 64, cfg.rows[t] = 16;
  _tile_loadconfig(&cfg);
  alignas(64) uint16_t ab[16 * 32];
  alignas(64) float c[16 * 16];
  for (int i = 0; i < 16 * 32; ++i) ab[i] = 0x3c00;  // bf16 1/128
  for (int i = 0; i < 16 * 16; ++i) c[i] = seed;
  _tile_loadd(0, c, 64);
  _tile_loadd(1, c, 64);
  _tile_loadd(2, c, 64);
  _tile_loadd(3, c, 64);
  _tile_loadd(4, ab, 64);
  _tile_loadd(5, ab, 64);
  _tile_loadd(6, ab, 64);
  _tile_loadd(7, ab, 64);
  for (int64_t i = 0; i < kIters / 16; ++i) {
    _tile_dpbf16ps(0, 4, 6);
    _tile_dpbf16ps(1, 4, 7);
    _tile_dpbf16ps(2, 5, 6);
    _tile_dpbf16ps(3, 5, 7);
  }
  _tile_stored(0, c, 64);
  float t = c[0];
  _tile_stored(3, c, 64);
  t += c[255];
  _tile_release();
  return t;
}

bool has_avx512() {
  return __builtin_cpu_supports("avx512f");
}
bool has_bf16() {
  return has_avx512() && __builtin_cpu_supports("avx512bf16");
}

void BM_PeakFp32Fma(benchmark::State& state) {
  const bool wide = has_avx512();
  const int lanes = wide ? 16 : 8;
  for (auto _ : state)
    benchmark::DoNotOptimize(wide ? fma_loop_avx512(float(state.thread_index()))
                                  : fma_loop_avx2(float(state.thread_index())));
  const double flops = double(kIters) * (wide ? kChains : kChainsYmm) * lanes * 2;
  state.counters["GFLOP/s"] =
      benchmark::Counter(flops * 1e-9, benchmark::Counter::kIsIterationInvariantRate |
                                           benchmark::Counter::kAvgThreads);
  state.SetLabel(wide ? "avx512 zmm" : "avx2 ymm");
}

void BM_PeakBf16Dot(benchmark::State& state) {
  if (!has_bf16()) {
    state.SkipWithError("this CPU has no AVX512_BF16");
    return;
  }
  for (auto _ : state) benchmark::DoNotOptimize(bf16_loop(float(state.thread_index())));
  const double flops = double(kIters) * kChains * 16 * 4;
  state.counters["GFLOP/s"] =
      benchmark::Counter(flops * 1e-9, benchmark::Counter::kIsIterationInvariantRate |
                                           benchmark::Counter::kAvgThreads);
  state.SetLabel("avx512_bf16 vdpbf16ps");
}

void BM_PeakAmxBf16(benchmark::State& state) {
  if (!has_amx_bf16()) {
    state.SkipWithError("this CPU (or kernel) offers no AMX-BF16");
    return;
  }
  for (auto _ : state) benchmark::DoNotOptimize(amx_loop(float(state.thread_index())));
  const double flops = double(kIters / 16) * 4 * 16 * 16 * 32 * 2;
  state.counters["GFLOP/s"] =
      benchmark::Counter(flops * 1e-9, benchmark::Counter::kIsIterationInvariantRate |
                                           benchmark::Counter::kAvgThreads);
  state.SetLabel("amx_bf16 tdpbf16ps");
}

// Each thread streams its own 3 × 64 MiB arrays (first-touched by that thread).
void BM_StreamTriad(benchmark::State& state) {
  const size_t n = (size_t(64) << 20) / sizeof(float);
  std::vector<float> a(n, 0.f), b(n, 1.f), c(n, 2.f);
  const float s = 3.f;
  for (auto _ : state) {
    float* __restrict pa = a.data();
    const float* __restrict pb = b.data();
    const float* __restrict pc = c.data();
    for (size_t i = 0; i < n; ++i) pa[i] = pb[i] + s * pc[i];
    benchmark::ClobberMemory();
  }
  state.counters["GB/s"] =
      benchmark::Counter(double(n) * 12 * 1e-9, benchmark::Counter::kIsIterationInvariantRate |
                                                    benchmark::Counter::kAvgThreads);
}

const int kCores = int(std::max(1u, std::thread::hardware_concurrency()));

}  // namespace

BENCHMARK(BM_PeakFp32Fma)->Threads(1)->Threads(kCores)->UseRealTime();
BENCHMARK(BM_PeakBf16Dot)->Threads(1)->Threads(kCores)->UseRealTime();
BENCHMARK(BM_PeakAmxBf16)->Threads(1)->Threads(kCores)->UseRealTime();
BENCHMARK(BM_StreamTriad)
    ->Threads(1)
    ->Threads(kCores)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
