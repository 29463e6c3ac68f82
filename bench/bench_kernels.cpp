// Kernel micro-benchmarks (Google Benchmark). Every case reports GFLOP/s through a counter:
// FLOPs = 2·in·out per layer per sample forward, ×3 for forward + backward (docs/ARCHITECTURE.md
// §6).
//   sirl_bench_kernels --benchmark_format=json > kernels.json
#include <benchmark/benchmark.h>

#include <algorithm>
#include <vector>

#include "engine/for_each_model.h"
#include "engine/train_step.h"
#include "kernels/adam_bf16_moments.h"
#include "kernels/rng.h"
#include "kernels/vae.h"

namespace {
using namespace sirl;

std::vector<float> random_inputs(int rows, int cols, Rng& rng) {
  std::vector<float> x(size_t(rows) * cols);
  for (auto& v : x) v = float(rng.normal());
  return x;
}

std::vector<float> init_params(const MlpShape& s, int models, Rng& rng) {
  std::vector<float> p(s.param_count() * models);
  for (int m = 0; m < models; ++m) mlp_init(s, p.data() + m * s.param_count(), rng);
  return p;
}

// One SIRL training step: 64 triplets (192 trajectories) through φ, triplet loss, backward, Adam.
// Args: {input width, hidden width, threads}.
void sirl_step(benchmark::State& state, bool bf16) {
  const int in = int(state.range(0)), hidden = int(state.range(1)), threads = int(state.range(2));
  const int B = 64, T = 1000;
  MlpShape s{{in, hidden, hidden, 6}};
  s.bf16_products = bf16;
  Rng rng(1);
  auto X = random_inputs(T, in, rng);
  Trainer t(s, AdamConfig{0.004, 0.99999}, init_params(s, 1, rng));
  std::vector<int32_t> trip(3 * B);
  for (auto& v : trip) v = int32_t(rng.uniform_int(T));
  for (auto _ : state)
    benchmark::DoNotOptimize(triplet_train_step(t, 0, adam_begin_step(t.adam_cfg, t.adam), X.data(),
                                                trip.data(), B, 1.f, threads));
  const double flops = 3 * s.forward_flops(3 * B);
  state.counters["GFLOP/s"] =
      benchmark::Counter(flops * 1e-9, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["steps/s"] = benchmark::Counter(1, benchmark::Counter::kIsIterationInvariantRate);
}
void BM_SirlStep(benchmark::State& state) {
  sirl_step(state, false);
}
// The same in precision "bf16" (kernels/gemm_bf16.h; FLOPs counted alike).
void BM_SirlStepBf16(benchmark::State& state) {
  sirl_step(state, true);
}
void sirl_step_args(benchmark::internal::Benchmark* b) {
  b->ArgNames({"in", "hidden", "threads"})
      ->Args({19, 128, 1})
      ->Args({19, 128, 2})
      ->Args({2037, 1024, 1})
      ->Args({2037, 1024, 2})
      ->Unit(benchmark::kMillisecond)
      ->UseRealTime();
}
BENCHMARK(BM_SirlStep)->Apply(sirl_step_args);
BENCHMARK(BM_SirlStepBf16)->Apply(sirl_step_args);

// One step of every model of t (Adam's next step for all), each model's step alone on its own
// pairs [M, B, 2] and labels [M, B], the models split over `threads`. Returns model 0's loss.
float step_every_model(Trainer& t, const float* X, const int32_t* pairs, const float* label, int B,
                       float l2, int threads) {
  const AdamStepScalars sc = adam_begin_step(t.adam_cfg, t.adam);
  for_each_model(t.models, threads, [&](int m) {
    preference_train_step(t, m, sc, X, pairs + size_t(m) * B * 2, label + size_t(m) * B, B, l2);
  });
  return t.losses[0];
}

// 20 TPA reward heads (6→h→h→1) trained side by side, 64 pairs (128 trajectories) each.
// Args: {hidden width, threads}.
void tpa_heads_step(benchmark::State& state, bool bf16) {
  const int hidden = int(state.range(0)), threads = int(state.range(1));
  const int M = 20, B = 64, T = 1000;
  MlpShape s{{6, hidden, hidden, 1}};
  s.bf16_products = bf16;
  Rng rng(2);
  auto X = random_inputs(T, 6, rng);
  Trainer t(s, AdamConfig{0.001, 1.0}, init_params(s, M, rng), M);
  std::vector<int32_t> pairs(size_t(M) * B * 2);
  std::vector<float> label(size_t(M) * B);
  for (auto& v : pairs) v = int32_t(rng.uniform_int(T));
  for (auto& v : label) v = float(rng.uniform_int(2));
  for (auto _ : state)
    benchmark::DoNotOptimize(
        step_every_model(t, X.data(), pairs.data(), label.data(), B, 10.f, threads));
  const double flops = 3 * s.forward_flops(2 * B) * M;
  state.counters["GFLOP/s"] =
      benchmark::Counter(flops * 1e-9, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["steps/s"] = benchmark::Counter(1, benchmark::Counter::kIsIterationInvariantRate);
}
void BM_TpaHeadsStep(benchmark::State& state) {
  tpa_heads_step(state, false);
}
void BM_TpaHeadsStepBf16(benchmark::State& state) {
  tpa_heads_step(state, true);
}
void tpa_heads_args(benchmark::internal::Benchmark* b) {
  b->ArgNames({"hidden", "threads"})
      ->Args({128, 1})
      ->Args({128, 2})
      ->Args({1024, 1})
      ->Args({1024, 2})
      ->Unit(benchmark::kMillisecond)
      ->UseRealTime();
}
BENCHMARK(BM_TpaHeadsStep)->Apply(tpa_heads_args);
BENCHMARK(BM_TpaHeadsStepBf16)->Apply(tpa_heads_args);

// A MultiPref-K step: φ (in→h→h→6) with K linear reward heads, B pairs (2B trajectories), each
// pair scored by its own human's head. Args: {input width, hidden width, K, threads}.
void BM_MultiPrefStep(benchmark::State& state) {
  const int in = int(state.range(0)), hidden = int(state.range(1)), K = int(state.range(2)),
            threads = int(state.range(3));
  const int B = 32, T = 400;
  MlpShape s{{in, hidden, hidden, 6}};
  Rng rng(7);
  auto X = random_inputs(T, in, rng);
  auto p = init_params(s, 1, rng);
  for (int k = 0; k < K * 7; ++k) p.push_back(float(rng.uniform(-0.4, 0.4)));
  Trainer t(s, AdamConfig{0.001, 1.0}, p);
  std::vector<int32_t> pairs(size_t(B) * 2), human(B);
  std::vector<float> label(B);
  for (auto& v : pairs) v = int32_t(rng.uniform_int(T));
  for (auto& v : human) v = int32_t(rng.uniform_int(K));
  for (auto& v : label) v = float(rng.uniform_int(2));
  for (auto _ : state)
    benchmark::DoNotOptimize(multihead_preference_train_step(
        t, 0, adam_begin_step(t.adam_cfg, t.adam), K, X.data(), pairs.data(), label.data(),
        human.data(), B, 10.f, threads));
  state.counters["GFLOP/s"] = benchmark::Counter(3 * s.forward_flops(2 * B) * 1e-9,
                                                 benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_MultiPrefStep)
    ->ArgNames({"in", "hidden", "K", "threads"})
    ->Args({19, 128, 10, 1})
    ->Args({2037, 1024, 10, 1})
    ->Args({2037, 1024, 10, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// An unfrozen TPA cell's step: 20 copies of φ (in→h→h→6, linear output) each with its own head
// (6→h→h→1), all fine-tuned side by side on B pairs each (2B trajectories). For JacoRobot
// (in 2037, h 1024) that is 20 × 4.2 M weights, Adam moments included 1 GB, streamed every step.
// Args: {input width, hidden width, pairs B, threads}.
void tpa_unfrozen_step(benchmark::State& state, bool bf16) {
  const int in = int(state.range(0)), hidden = int(state.range(1)), B = int(state.range(2)),
            threads = int(state.range(3));
  const int M = 20, T = 400;
  MlpShape s{{in, hidden, hidden, 6, hidden, hidden, 1}};
  s.linear_layers = {2};
  s.bf16_products = bf16;
  Rng rng(5);
  auto X = random_inputs(T, in, rng);
  Trainer t(s, AdamConfig{0.001, 1.0}, init_params(s, M, rng), M);
  std::vector<int32_t> pairs(size_t(M) * B * 2);
  std::vector<float> label(size_t(M) * B);
  for (auto& v : pairs) v = int32_t(rng.uniform_int(T));
  for (auto& v : label) v = float(rng.uniform_int(2));
  for (auto _ : state)
    benchmark::DoNotOptimize(
        step_every_model(t, X.data(), pairs.data(), label.data(), B, 10.f, threads));
  const double flops = 3 * s.forward_flops(2 * B) * M;
  state.counters["GFLOP/s"] =
      benchmark::Counter(flops * 1e-9, benchmark::Counter::kIsIterationInvariantRate);
  // Bytes a step must move at least: weights read forward and backward, Adam's p, m, v read and
  // written once (the fused pass; before it, also a gradient written, zeroed and re-read).
  const double bytes = 8.0 * 4 * double(s.param_count()) * M;
  state.counters["GB/s"] =
      benchmark::Counter(bytes * 1e-9, benchmark::Counter::kIsIterationInvariantRate);
}
void BM_TpaUnfrozenStep(benchmark::State& state) {
  tpa_unfrozen_step(state, false);
}
void BM_TpaUnfrozenStepBf16(benchmark::State& state) {
  tpa_unfrozen_step(state, true);
}
void tpa_unfrozen_args(benchmark::internal::Benchmark* b) {
  b->ArgNames({"in", "hidden", "B", "threads"})
      ->Args({19, 128, 32, 1})
      ->Args({2037, 1024, 10, 1})
      ->Args({2037, 1024, 32, 1})
      ->Args({2037, 1024, 32, 2})
      ->Unit(benchmark::kMillisecond)
      ->UseRealTime();
}
BENCHMARK(BM_TpaUnfrozenStep)->Apply(tpa_unfrozen_args);
BENCHMARK(BM_TpaUnfrozenStepBf16)->Apply(tpa_unfrozen_args);

// φ forward + backward alone (no loss, no optimizer) on `batch` rows, one thread.
// Args: {input width, hidden width, batch}.
void BM_MlpForwardBackward(benchmark::State& state) {
  const int in = int(state.range(0)), hidden = int(state.range(1)), B = int(state.range(2));
  MlpShape s{{in, hidden, hidden, 6}};
  Rng rng(3);
  auto X = random_inputs(B, in, rng);
  auto p = init_params(s, 1, rng);
  auto dout = random_inputs(B, 6, rng);
  std::vector<float> g(p.size());
  MlpTape<float> tape;
  for (auto _ : state) {
    mlp_forward(s, p.data(), X.data(), B, tape);
    mlp_backward(s, p.data(), tape, dout.data(), g.data(), static_cast<float*>(nullptr));
    benchmark::DoNotOptimize(g.data());
  }
  state.counters["GFLOP/s"] = benchmark::Counter(3 * s.forward_flops(B) * 1e-9,
                                                 benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_MlpForwardBackward)
    ->ArgNames({"in", "hidden", "batch"})
    ->Args({19, 128, 64})
    ->Args({19, 128, 192})
    ->Args({2037, 1024, 64})
    ->Args({2037, 1024, 192})
    ->UseRealTime();

// One VAE step (ELBO forward + backward + Adam), the paper's batch of 32.
// Args: {input width, hidden width, fused, threads}: fused = 1 is what training runs
// (vae_loss_and_adam_step: Adam inside the backward pass, no gradient buffer); fused = 0 the
// gradient into a zeroed buffer, then Adam over it (the same bits; kept to measure the fusion).
// threads: the cores one VAE task gets when the scheduler widens it (JacoRobot's VAE is the
// paper's critical path; `sirl plan` needs what a second core buys it).
void BM_VaeStep(benchmark::State& state) {
  const int in = int(state.range(0)), hidden = int(state.range(1)), B = 32, L = 6;
  const bool fused = state.range(2) != 0;
  const int threads = int(state.range(3));
  const VaeShape s = make_vae_shape(in, {hidden, hidden}, L);
  Rng rng(4);
  auto X = random_inputs(B, in, rng);
  auto eps = random_inputs(B, L, rng);
  std::vector<float> p(s.param_count()), g(fused ? 0 : s.param_count());
  mlp_init(s.encoder, p.data(), rng);
  mlp_init(s.decoder, p.data() + s.encoder.param_count(), rng);
  AdamConfig cfg{0.01, 0.99999};
  AdamState adam(p.size());
  VaeWorkspace<float> ws;
  for (auto _ : state) {
    if (fused) {
      const AdamStepScalars step = adam_begin_step(cfg, adam);
      benchmark::DoNotOptimize(vae_loss_and_adam_step(s, p.data(), X.data(), B, eps.data(), 0.01f,
                                                      VaeElbo::sum_over_inputs, step, adam.m.data(),
                                                      adam.v.data(), ws, nullptr, threads));
    } else {
      std::fill(g.begin(), g.end(), 0.f);
      benchmark::DoNotOptimize(vae_loss_and_grad(s, p.data(), X.data(), B, eps.data(), 0.01f,
                                                 VaeElbo::sum_over_inputs, g.data(), ws, nullptr,
                                                 threads));
      adam_step(cfg, adam, p.data(), g.data(), p.size());
    }
  }
  const double flops = 3 * (s.encoder.forward_flops(B) + s.decoder.forward_flops(B));
  state.counters["GFLOP/s"] =
      benchmark::Counter(flops * 1e-9, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_VaeStep)
    ->ArgNames({"in", "hidden", "fused", "threads"})
    ->ArgsProduct({{19}, {128}, {0, 1}, {1}})
    ->ArgsProduct({{2037}, {1024}, {0, 1}, {1}})
    ->Args({2037, 1024, 1, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// One Adam update over n parameters (kernels/adam.h), moments in fp32 (bf16 = 0: 28 bytes a
// parameter moved: p, g, m, v read, p, m, v written) or bf16 (bf16 = 1: 20 bytes;
// kernels/adam_bf16_moments.h). n = 3.1 M is a JacoRobot reward head with its own copy of φ (far
// beyond the caches: the memory-bound case), 64 Ki a GridRobot network's (in cache). The counter
// is the bytes the update must move over its time.
void BM_AdamUpdate(benchmark::State& state) {
  const size_t n = size_t(state.range(0));
  const bool bf16 = state.range(1) != 0;
  Rng rng(5);
  std::vector<float> p(n), g(n), m(bf16 ? 0 : n, 0.f), v(bf16 ? 0 : n, 0.f);
  std::vector<uint16_t> m16(bf16 ? n : 0, 0), v16(bf16 ? n : 0, 0);
  for (size_t i = 0; i < n; ++i) p[i] = float(rng.normal()), g[i] = float(rng.normal()) * 1e-2f;
  const AdamConfig cfg{0.001, 1.0};
  int64_t t = 0;
  for (auto _ : state) {
    const AdamStepScalars s = adam_step_scalars(cfg, ++t);
    if (bf16)
      adam_apply_bf16_moments(s, p.data(), g.data(), m16.data(), v16.data(), n);
    else
      adam_apply(s, p.data(), g.data(), m.data(), v.data(), n);
    benchmark::ClobberMemory();
  }
  state.counters["GB/s"] = benchmark::Counter(double(n) * (bf16 ? 20 : 28) * 1e-9,
                                              benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_AdamUpdate)
    ->ArgNames({"n", "bf16"})
    ->ArgsProduct({{1 << 16, 3'100'000}, {0, 1}})
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
