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
// The loops are the engine's own (probes/peak_loops.h: `sirl run` measures its roofs with them
// briefly); the instruction set is chosen at run time, like the engine's kernels.
#include <benchmark/benchmark.h>

#include <cstdint>
#include <thread>
#include <vector>

#include "probes/peak_loops.h"

namespace {

using namespace sirl;

constexpr int64_t kIters = 1 << 16;  // per benchmark iteration

bool has_avx512() {
  return __builtin_cpu_supports("avx512f");
}

void BM_PeakFp32Fma(benchmark::State& state) {
  const bool wide = has_avx512();
  for (auto _ : state)
    benchmark::DoNotOptimize(wide ? fma_loop_avx512(kIters, float(state.thread_index()))
                                  : fma_loop_avx2(kIters, float(state.thread_index())));
  const double flops = fma_loop_flops(wide, kIters);
  state.counters["GFLOP/s"] =
      benchmark::Counter(flops * 1e-9, benchmark::Counter::kIsIterationInvariantRate |
                                           benchmark::Counter::kAvgThreads);
  state.SetLabel(wide ? "avx512 zmm" : "avx2 ymm");
}

void BM_PeakBf16Dot(benchmark::State& state) {
  if (!has_avx512_bf16()) {
    state.SkipWithError("this CPU has no AVX512_BF16");
    return;
  }
  for (auto _ : state) benchmark::DoNotOptimize(dpbf16_loop(kIters, float(state.thread_index())));
  const double flops = dpbf16_loop_flops(kIters);
  state.counters["GFLOP/s"] =
      benchmark::Counter(flops * 1e-9, benchmark::Counter::kIsIterationInvariantRate |
                                           benchmark::Counter::kAvgThreads);
  state.SetLabel("avx512_bf16 vdpbf16ps");
}

void BM_PeakAmxBf16(benchmark::State& state) {
  if (!amx_bf16_usable()) {
    state.SkipWithError("this CPU (or kernel) offers no AMX-BF16");
    return;
  }
  for (auto _ : state) benchmark::DoNotOptimize(amx_bf16_loop(kIters, float(state.thread_index())));
  const double flops = amx_bf16_loop_flops(kIters);
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
