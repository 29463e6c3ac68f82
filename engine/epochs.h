// Mini-batch order for one epoch, as PyTorch's DataLoader(shuffle=True, drop_last=False):
// a fresh permutation of the n examples each epoch, cut into batches of `batch` (the last one
// shorter when batch does not divide n).
#pragma once
#include <algorithm>
#include <cstdint>
#include <functional>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "engine/checkpoint.h"
#include "engine/convergence.h"
#include "engine/execution.h"
#include "engine/for_each_model.h"
#include "kernels/rng.h"

namespace sirl {

// Fisher–Yates shuffle of 0..n−1 into `order` (resized).
inline void shuffle_order(int64_t n, Rng& rng, std::vector<int32_t>& order) {
  order.resize(n);
  std::iota(order.begin(), order.end(), 0);
  for (int64_t i = n - 1; i > 0; --i) std::swap(order[i], order[rng.uniform_int(uint64_t(i + 1))]);
}

// Checkpoints of an epoch loop: the epoch reached, the curve(s) so far and the order streams,
// plus what the training adds through `r.save` / `r.restore`.
namespace epochs_detail {
inline bool resume(const ResumableState* r, int epochs, TrainingSnapshot& s) {
  if (!r || !r->checkpointer || !r->checkpointer->load(s)) return false;
  if (s.epoch < 1 || s.epoch >= epochs)
    throw std::runtime_error("training checkpoint at epoch " + std::to_string(s.epoch) + " of " +
                             std::to_string(epochs) + " (another training?)");
  r->restore(s);
  return true;
}
inline bool due(const ResumableState* r, int done, int epochs) {
  return r && r->checkpointer && done < epochs && r->checkpointer->due();
}
inline void save(const ResumableState* r, TrainingSnapshot& s) {
  r->save(s);
  r->checkpointer->save(s);
}
// R models' loop state: curves [R, epochs], each model's order stream, the epochs each model has
// run and whether it has stopped (a snapshot without the last two, from a loop whose models could
// not stop early, leaves every model running at the snapshot's epoch). Returns the epoch a saved
// state resumes from (0: none). A single model's snapshot of engine 0.12 and before holds its
// curve so far as "loop/curve" and its stream as "loop/order": read as model 0's.
inline int resume_models(const ResumableState* r, int epochs, std::vector<float>& curves,
                         std::vector<Rng>& rngs, std::vector<int>& epochs_run,
                         std::vector<char>& stopped) {
  TrainingSnapshot s;
  if (!resume(r, epochs, s)) return 0;
  const size_t R = rngs.size();
  if (R == 1 && !s.floats.count("loop/curves") && s.floats.count("loop/curve")) {
    const std::vector<float>& c = s.get("loop/curve", size_t(s.epoch));
    std::copy(c.begin(), c.end(), curves.begin());
    s.get_rng("loop/order", rngs[0]);
  } else {
    curves = s.get("loop/curves", curves.size());
    for (size_t m = 0; m < R; ++m) s.get_rng("loop/order/" + std::to_string(m), rngs[m]);
  }
  epochs_run.assign(R, s.epoch);
  if (s.floats.count("loop/epochs_run")) {
    const std::vector<float>& run = s.get("loop/epochs_run", R);
    for (size_t m = 0; m < R; ++m) {
      if (!(run[m] >= 1 && run[m] <= float(s.epoch)))
        throw std::runtime_error("training checkpoint: a model at epoch " + std::to_string(run[m]) +
                                 " of " + std::to_string(s.epoch));
      epochs_run[m] = int(run[m]);
    }
  }
  stopped.assign(R, 0);
  if (s.floats.count("loop/stopped")) {
    const std::vector<float>& st = s.get("loop/stopped", R);
    for (size_t m = 0; m < R; ++m) stopped[m] = st[m] != 0;
  }
  return s.epoch;
}
inline void save_models(const ResumableState* r, int epoch, const std::vector<float>& curves,
                        const std::vector<Rng>& rngs, const std::vector<int>& epochs_run,
                        const std::vector<char>& stopped) {
  TrainingSnapshot s;
  s.epoch = epoch;
  s.floats["loop/curves"] = curves;
  s.floats["loop/epochs_run"].assign(epochs_run.begin(), epochs_run.end());
  s.floats["loop/stopped"].assign(stopped.begin(), stopped.end());
  for (size_t m = 0; m < rngs.size(); ++m) s.put_rng("loop/order/" + std::to_string(m), rngs[m]);
  save(r, s);
}
}  // namespace epochs_detail

// The epoch loop of every training: R ≥ 1 independent models, each `epochs` passes over its n
// examples in shuffled mini-batches (shuffle_order from its own stream rngs[m]), model m's steps
// of a stretch of epochs in a row before the next model's (the models split over `threads`).
// Training 20 TPA heads side by side would stream every head's weights and Adam moments from
// memory each step (a JacoRobot head with its copy of φ is 50 MB); one model's steps in a row
// find more of them in cache. The models share nothing they write, so every model's bits and
// the curves are the same for any thread count, stretch or resume.
// step(m, rows, b, t) trains model m on the b example indices rows[0..b) as its t-th optimizer
// step (1-based, counted from the start of this loop: epoch e's i-th batch is
// e·⌈n/batch⌉ + i + 1, so Adam's step is derived, never patched) and returns that batch's mean
// loss. at_epoch(e) is called whenever every model that still trains stands at the end of epoch
// e (before a checkpoint is asked for, and at the end), for the caller to bring shared state
// there.
struct EpochLoopOptions {
  const ResumableState* resume = nullptr;  // checkpoints: picked up first, saved when due
  int threads = 1;                         // threads the models split over (R > 1)
  // Stretches: whole epochs, enough for ≥ `stretch_steps` steps of a model in a row (0: one
  // epoch, every model's epoch e before any model's e + 1: lockstep by epochs). Checkpoints are
  // asked for after each, so a stretch is also what a crash can lose. Only the speed and the
  // spacing of checkpoints depend on it, never the result.
  int stretch_steps = kStretchSteps;
  // Stopping (engine/convergence.h): each model is asked after each of its epochs but the last
  // whether its own curve so far has converged; a model that stops takes no further step (its
  // FLOPs are not spent) and its curve is NaN from there on.
  StopRule stop;
  // The exact skip: at_fixed_point(m, done), when given, is asked after each of model m's epochs
  // but the last (`done` epochs run) whether the model stands at a fixed point: every further
  // step would leave every weight bit unchanged and every further epoch's loss would equal this
  // one's. If so the model takes no further step and its remaining epochs get that loss: its
  // weights and curve are the full run's.
  std::function<bool(int, int)> at_fixed_point;
  // A second rule that only watches (the shadow): at_shadow_stop(m, done), when given, is called
  // once, after the first of model m's epochs but the last at which `shadow` would have stopped
  // it, and the model trains on. Its weights then are bit for bit those of a run stopped by that
  // rule, so the caller can score that run's model from this one. On resume a model whose curve
  // already met the shadow rule is not called again (the caller keeps what it recorded).
  StopRule shadow;
  std::function<void(int, int)> at_shadow_stop;
};
struct ModelCurves {
  std::vector<float> curves;    // [R, epochs]: each epoch's mean loss; NaN after a model stopped
  std::vector<int> epochs_run;  // [R] epochs each model executed (< epochs: stopped or skipped)
};
// An exception from `step` (out of memory, say) ends the stretch and is rethrown here, before any
// checkpoint (for_each_model).
template <typename Step, typename AtEpoch>
ModelCurves run_model_epochs(int64_t n, int epochs, int batch, std::vector<Rng>& rngs, Step&& step,
                             AtEpoch&& at_epoch, const EpochLoopOptions& opt = {}) {
  const int R = int(rngs.size());
  ModelCurves out;
  out.curves.assign(size_t(R) * size_t(epochs), 0.f);
  out.epochs_run.assign(size_t(R), n > 0 ? epochs : 0);
  if (n <= 0) return out;
  const int64_t per_epoch = (n + batch - 1) / batch;
  out.epochs_run.assign(size_t(R), 0);
  std::vector<char> stopped(size_t(R), 0);
  const int first =
      epochs_detail::resume_models(opt.resume, epochs, out.curves, rngs, out.epochs_run, stopped);
  // Which models' shadow rule has fired: from the curves, so a resumed loop knows it too.
  std::vector<char> shadowed(size_t(R), 0);
  if (opt.at_shadow_stop)
    for (int m = 0; m < R; ++m)
      for (int e = 1; e <= std::min(first, epochs - 1) && !shadowed[m]; ++e)
        shadowed[m] = stops_after(opt.shadow, out.curves.data() + size_t(m) * epochs, e);
  const int stretch =
      int(std::max<int64_t>(1, (std::max(1, opt.stretch_steps) + per_epoch - 1) / per_epoch));
  auto all_stopped = [&] {
    return std::all_of(stopped.begin(), stopped.end(), [](char x) { return x != 0; });
  };
  for (int e0 = first; e0 < epochs && !all_stopped(); e0 += stretch) {
    const int e1 = std::min(epochs, e0 + stretch);
    // One model alone keeps every thread for its own steps (no parallel region around it).
    for_each_model(R, R > 1 ? opt.threads : 1, [&](int m) {
      if (stopped[m]) return;
      float* curve = out.curves.data() + size_t(m) * epochs;
      std::vector<int32_t> order;
      for (int e = e0; e < e1; ++e) {
        shuffle_order(n, rngs[m], order);
        double sum = 0;
        for (int64_t i0 = 0; i0 < n; i0 += batch) {
          const int b = int(n - i0 < batch ? n - i0 : batch);
          const int64_t t = int64_t(e) * per_epoch + i0 / batch + 1;
          sum += double(step(m, order.data() + i0, b, t)) * b;
        }
        curve[e] = float(sum / double(n));
        out.epochs_run[m] = e + 1;
        if (e + 1 >= epochs) continue;
        if (opt.at_shadow_stop && !shadowed[m] && stops_after(opt.shadow, curve, e + 1)) {
          shadowed[m] = 1;
          opt.at_shadow_stop(m, e + 1);
        }
        if (opt.at_fixed_point && opt.at_fixed_point(m, e + 1)) {
          stopped[m] = 1;
          std::fill(curve + e + 1, curve + epochs, curve[e]);
          break;
        }
        if (stops_after(opt.stop, curve, e + 1)) {
          stopped[m] = 1;
          std::fill(curve + e + 1, curve + epochs, std::numeric_limits<float>::quiet_NaN());
          break;
        }
      }
    });
    at_epoch(e1);
    // Nothing is left to resume once every model has stopped (a caller's record of why a model
    // stopped lives in its own closure, which a snapshot does not hold).
    if (all_stopped()) break;
    if (epochs_detail::due(opt.resume, e1, epochs))
      epochs_detail::save_models(opt.resume, e1, out.curves, rngs, out.epochs_run, stopped);
  }
  return out;
}

// One model (run_model_epochs with R = 1, one epoch a stretch): step(rows, b) trains on the b
// example indices rows[0..b) and returns that batch's mean loss. Returns each epoch's mean loss
// (empty when n = 0). at_fixed_point(done) and stop as EpochLoopOptions' for this model (a stopped
// model's curve is NaN from its stop on).
template <typename Step>
std::vector<float> run_epochs(int64_t n, int epochs, int batch, Rng& rng, Step&& step,
                              const ResumableState* resume = nullptr,
                              const std::function<bool(int)>& at_fixed_point = {},
                              const StopRule& stop = {}) {
  if (n <= 0) return {};
  std::vector<Rng> rngs{rng};
  EpochLoopOptions opt;
  opt.resume = resume;
  opt.stretch_steps = 0;
  opt.stop = stop;
  if (at_fixed_point) opt.at_fixed_point = [&](int, int done) { return at_fixed_point(done); };
  ModelCurves run = run_model_epochs(
      n, epochs, batch, rngs,
      [&](int, const int32_t* rows, int b, int64_t) { return step(rows, b); }, [](int) {}, opt);
  rng = rngs[0];
  return std::move(run.curves);
}

}  // namespace sirl
