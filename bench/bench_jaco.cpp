// JacoRobot generation: forward-kinematics waypoints per second (MuJoCo), deformation solves per
// second (CHOLMOD, one factor reused), and the whole 10,000-trajectory dataset (target: < 30 s).
#include <benchmark/benchmark.h>

#include <vector>

#include "datasets/jaco_robot.h"
#include "datasets/trajectory_deformation.h"
#include "kernels/rng.h"

namespace {

void BM_JacoFk(benchmark::State& state) {
  sirl::JacoKinematics kin;
  sirl::Rng rng(1);
  std::vector<double> q(7 * 1024);
  for (double& x : q) x = rng.uniform(0.8, 5.0);
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(kin.frames(q.data() + 7 * (i++ % 1024)));
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["waypoints/s"] =
      benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_JacoFk);

// Solves of A x = ũ (21 waypoints, 7 joints) with `k` right-hand sides per CHOLMOD call.
void BM_DeformationSolve(benchmark::State& state) {
  const int k = int(state.range(0));
  sirl::DeformationNorm norm(21, 7);
  std::vector<double> B(size_t(norm.size()) * k), work;
  sirl::Rng rng(2);
  for (double& x : B) x = rng.uniform(-1, 1);
  for (auto _ : state) {
    work = B;
    norm.solve(work.data(), k);
    benchmark::DoNotOptimize(work.data());
  }
  state.counters["solves/s"] =
      benchmark::Counter(double(state.iterations()) * k, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_DeformationSolve)->Arg(1)->Arg(256);

void BM_JacoDataset(benchmark::State& state) {
  sirl::JacoConfig c;
  c.trajectories = state.range(0);
  c.threads = int(state.range(1));
  for (auto _ : state) benchmark::DoNotOptimize(sirl::make_jaco_dataset(c).inputs.data());
  state.counters["trajectories/s"] =
      benchmark::Counter(double(state.iterations()) * c.trajectories, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_JacoDataset)->Args({10000, 1})->Args({10000, 2})->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
