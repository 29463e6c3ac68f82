// The plan's cost model, in one room: what a task is expected to compute, hold and stream, from
// which `sirl plan`, `sirl submit` and `sirl run` (its ETA, its memory bound) predict a run.
//   - what each task computes: its kind's `cost` (experiment/simulation_costs.cpp for the
//     paper's grid, experiment/study_tasks.cpp for the study), from the sizes and memory model
//     here and the epochs a training is expected to run (experiment/expected_epochs.h);
//   - how fast this machine computes it: its kind's RateClass, timed on a calibration sample
//     (experiment/calibration.h);
//   - the wall time: the scheduler simulated over those times (jobs/estimate.h,
//     jobs/schedule_sim.h), with the main-memory bandwidth below shared by streaming tasks.
#pragma once
#include <cstdint>

#include "experiment/task.h"
#include "kernels/mlp.h"

namespace sirl {

// φ's shape and the trajectory space of one environment under a profile (the task's resolved
// hyper-parameters).
struct EnvSizes {
  const Hyper& h;
  int input_dim;
  int64_t trajectories;
  MlpShape phi;
};
EnvSizes env_sizes(const Task& t, const Profile& p);

// Bytes of one training: params, gradient, Adam's m and v, and one batch's activations.
double working_set(const MlpShape& s, int batch_rows);

// Main-memory traffic of an Adam training whose state does not fit a core's share of the caches
// (kCacheShare); 0 when it does. `models` step side by side (an active-selection ensemble).
inline constexpr double kCacheShare = 5.0 * 1024 * 1024;
double stream_bytes(const MlpShape& s, int64_t rows_per_epoch, int batch, int epochs,
                    int models = 1);

// FLOPs of FPE's linear probe over `rows` rows of a d-wide φ(ξ).
double probe_flops(int64_t rows, int d);

// The width of φ(ξ) a cell's probe or head reads: the embedding's; the raw reference's is the
// input's, truth's the features' (at most 8 in every environment: an estimate).
int probed_width(const Task& t, const EnvSizes& z);

// Main-memory bandwidth of a node of `cores` cores when the user names none (--node-bandwidth):
// the STREAM triad per core of the 2-core machines the defaults were measured on
// (docs/roofline.md), times the cores, up to what a 12-channel DDR5-4800 socket delivers.
double default_node_bandwidth(int cores);

}  // namespace sirl
