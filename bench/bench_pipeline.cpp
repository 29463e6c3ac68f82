// Whole units of work, the same ones bench/torch_reference.py does in PyTorch: a SIRL training
// run (N triplets, E epochs) and a TPA cell (20 reward heads, M pairs, E epochs, frozen φ), at
// Grid and Jaco sizes; and the latency of committing one task's results to HDF5.
#include <benchmark/benchmark.h>

#include <filesystem>

#include "datasets/grid_robot.h"
#include "datasets/jaco_robot.h"
#include "datasets/query_bundle.h"
#include "engine/methods.h"
#include "engine/tpa.h"
#include "jobs/memory_reuse.h"
#include "results/task_store.h"

namespace {

// As `sirl` does at the start of main (jobs/memory_reuse.h): the cells here allocate and free
// their heads as a run's tasks do.
[[maybe_unused]] const bool kMemoryReuse = (sirl::keep_freed_memory_for_reuse(), true);

using namespace sirl;

struct World {
  Dataset d;
  QueryBundle b;
};
const World& world(bool jaco) {
  static World grid, jac;
  World& w = jaco ? jac : grid;
  if (w.d.count == 0) {
    if (jaco) {
      JacoConfig c;
      c.trajectories = 2000;
      w.d = make_jaco_dataset(c);
    } else {
      w.d = make_grid_dataset();
    }
    QueryBundleConfig qc;
    w.b = make_query_bundle(w.d, qc, 1);
  }
  return w;
}

// Grid: N = 1000 triplets × 10 epochs (160 steps). Jaco: N = 200 × 2 epochs (8 steps).
void BM_SirlTrainingRun(benchmark::State& state) {
  const bool jaco = state.range(0) == 1;
  const World& w = world(jaco);
  Hyper h = paper_hyper(jaco ? "jaco" : "grid");
  h.sirl.epochs = jaco ? 2 : 10;
  const MethodConfig c{Method::sirl, jaco ? 200 : 1000, false, h};
  double flops = 0;
  for (auto _ : state) flops = train_representation(w.d, w.b, c, 7).train_flops;
  state.counters["GFLOP/s"] =
      benchmark::Counter(flops * 1e-9, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_SirlTrainingRun)
    ->ArgName("jaco")
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// One TPA cell (20 heads, M pairs each) on a freshly initialised φ, `epochs` epochs.
void time_tpa_cell(benchmark::State& state, bool jaco, int epochs, int64_t M, bool frozen) {
  const World& w = world(jaco);
  Hyper h = paper_hyper(jaco ? "jaco" : "grid");
  h.tpa.epochs = epochs;
  Representation phi;
  phi.shape = phi_shape(w.d.input_dim, h);
  phi.params.resize(phi.shape.param_count());
  Rng rng(3);
  mlp_init(phi.shape, phi.params.data(), rng);
  double flops = 0;
  for (auto _ : state)
    flops = evaluate_tpa(phi, w.d, w.b.tpa, TpaConfig{M, frozen, h}, 5).train_flops;
  state.counters["GFLOP/s"] =
      benchmark::Counter(flops * 1e-9, benchmark::Counter::kIsIterationInvariantRate);
}

// 20 heads, M = 100 pairs each, frozen φ. Grid: 20 epochs. Jaco: 2 epochs.
void BM_TpaCell(benchmark::State& state) {
  const bool jaco = state.range(0) == 1;
  time_tpa_cell(state, jaco, jaco ? 2 : 20, 100, true);
}
BENCHMARK(BM_TpaCell)
    ->ArgName("jaco")
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The smallest cells of a quick run: 20 heads, M = 10 pairs each (one step an epoch), JacoRobot,
// 15 epochs as quick's profile has them; frozen (heads only) and unfrozen (each head fine-tunes
// its own copy of φ). Few FLOPs a byte: the cells that run at the lowest rate of a quick run.
void BM_TpaSmallCell(benchmark::State& state) {
  time_tpa_cell(state, true, 15, 10, state.range(0) == 1);
}
BENCHMARK(BM_TpaSmallCell)
    ->ArgName("frozen")
    ->Arg(1)
    ->Arg(0)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Quick's largest JacoRobot cells: 20 heads, M = 100 pairs each (two steps an epoch), 15 epochs,
// frozen and unfrozen, trained as the engine trains them (one head after another): the frozen
// JacoRobot cell of README's performance targets, measured whole rather than as one step of all
// 20 heads (BM_TpaHeadsStep).
void BM_TpaQuickCell(benchmark::State& state) {
  time_tpa_cell(state, true, 15, 100, state.range(0) == 1);
}
BENCHMARK(BM_TpaQuickCell)
    ->ArgName("frozen")
    ->Arg(1)
    ->Arg(0)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Committing one representation's record (weights + loss curve): Grid φ (18k floats) and
// Jaco φ (3.1 M floats), atomically (temporary file, fsync, rename).
void BM_TaskCommit(benchmark::State& state) {
  const bool jaco = state.range(0) == 1;
  const auto dir = std::filesystem::temp_directory_path() / "sirl_bench_commit";
  std::filesystem::remove_all(dir);
  TaskStore store(dir);
  TaskRecord r;
  r.key = "bench/rep";
  r.kind = "rep";
  const MlpShape s = phi_shape(jaco ? 2037 : 19, paper_hyper(jaco ? "jaco" : "grid"));
  r.arrays["params"] = {{s.param_count()}, std::vector<float>(s.param_count(), 0.5f)};
  r.arrays["loss_curve"] = {{3000}, std::vector<float>(3000, 1.f)};
  r.num["seconds"] = 1;
  for (auto _ : state) store.commit(r);
  state.counters["commits/s"] =
      benchmark::Counter(1, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["MB/s"] = benchmark::Counter(4e-6 * double(s.param_count()),
                                              benchmark::Counter::kIsIterationInvariantRate);
  std::filesystem::remove_all(dir);
}
BENCHMARK(BM_TaskCommit)
    ->ArgName("jaco")
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
