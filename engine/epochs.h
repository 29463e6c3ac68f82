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
// R models' loop state: curves [R, epochs], each model's order stream and, when asked for, the
// epochs each model has run and whether it has stopped (a snapshot without them, from a loop
// whose models could not stop early, leaves every model running at the snapshot's epoch). Returns
// the epoch a saved state resumes from (0: none).
inline int resume_models(const ResumableState* r, int epochs, std::vector<float>& curves,
                         std::vector<Rng>& rngs, std::vector<int>* epochs_run = nullptr,
                         std::vector<char>* stopped = nullptr) {
  TrainingSnapshot s;
  if (!resume(r, epochs, s)) return 0;
  curves = s.get("loop/curves", curves.size());
  for (size_t m = 0; m < rngs.size(); ++m) s.get_rng("loop/order/" + std::to_string(m), rngs[m]);
  if (epochs_run) {
    epochs_run->assign(rngs.size(), s.epoch);
    if (auto it = s.floats.find("loop/epochs_run"); it != s.floats.end()) {
      const std::vector<float>& run = s.get("loop/epochs_run", rngs.size());
      for (size_t m = 0; m < rngs.size(); ++m) {
        if (!(run[m] >= 1 && run[m] <= float(s.epoch)))
          throw std::runtime_error("training checkpoint: a model at epoch " +
                                   std::to_string(run[m]) + " of " + std::to_string(s.epoch));
        (*epochs_run)[m] = int(run[m]);
      }
    }
  }
  if (stopped) {
    stopped->assign(rngs.size(), 0);
    if (auto it = s.floats.find("loop/stopped"); it != s.floats.end()) {
      const std::vector<float>& st = s.get("loop/stopped", rngs.size());
      for (size_t m = 0; m < rngs.size(); ++m) (*stopped)[m] = st[m] != 0;
    }
  }
  return s.epoch;
}
inline void save_models(const ResumableState* r, int epoch, const std::vector<float>& curves,
                        const std::vector<Rng>& rngs, const std::vector<int>* epochs_run = nullptr,
                        const std::vector<char>* stopped = nullptr) {
  TrainingSnapshot s;
  s.epoch = epoch;
  s.floats["loop/curves"] = curves;
  if (epochs_run) s.floats["loop/epochs_run"].assign(epochs_run->begin(), epochs_run->end());
  if (stopped) s.floats["loop/stopped"].assign(stopped->begin(), stopped->end());
  for (size_t m = 0; m < rngs.size(); ++m) s.put_rng("loop/order/" + std::to_string(m), rngs[m]);
  save(r, s);
}
}  // namespace epochs_detail

// `epochs` passes over n examples in shuffled mini-batches. step(rows, b) trains on the b example
// indices rows[0..b) and returns that batch's mean loss. Returns each epoch's mean loss.
// With `resume`, a saved state is picked up first and the state is saved after epochs when the
// checkpointer says so; the result is the same bits either way.
// `at_fixed_point(done)`, when given, is asked after every epoch but the last (`done` epochs run)
// whether the training
// stands at a fixed point: every further step would leave every weight bit unchanged and every
// further epoch's loss would equal this one's. If so the loop ends there and the remaining epochs
// get that loss: the weights and the curve are the full run's (the exact skip).
template <typename Step>
std::vector<float> run_epochs(int64_t n, int epochs, int batch, Rng& rng, Step&& step,
                              const ResumableState* resume = nullptr,
                              const std::function<bool(int)>& at_fixed_point = {}) {
  std::vector<float> curve;
  std::vector<int32_t> order;
  int first = 0;
  if (TrainingSnapshot s; n > 0 && epochs_detail::resume(resume, epochs, s)) {
    first = s.epoch;
    curve = s.get("loop/curve", size_t(first));
    s.get_rng("loop/order", rng);
  }
  for (int e = first; e < epochs && n > 0; ++e) {
    shuffle_order(n, rng, order);
    double sum = 0;
    for (int64_t i0 = 0; i0 < n; i0 += batch) {
      const int b = int(n - i0 < batch ? n - i0 : batch);
      sum += double(step(order.data() + i0, b)) * b;
    }
    curve.push_back(float(sum / double(n)));
    if (e + 1 < epochs && at_fixed_point && at_fixed_point(e + 1)) {
      curve.resize(size_t(epochs), curve.back());
      break;
    }
    if (epochs_detail::due(resume, e + 1, epochs)) {
      TrainingSnapshot s;
      s.epoch = e + 1;
      s.floats["loop/curve"] = curve;
      s.put_rng("loop/order", rng);
      epochs_detail::save(resume, s);
    }
  }
  return curve;
}

// The same for R models trained side by side on n examples each, every model with its own order
// stream rngs[m] (shuffled in model order each epoch). step(orders, b) trains model m on
// orders[m][0..b) and returns the R batch losses. Returns the curves [R, epochs].
template <typename Step>
std::vector<float> run_epochs_batched(int64_t n, int epochs, int batch, std::vector<Rng>& rngs,
                                      Step&& step, const ResumableState* resume = nullptr) {
  const size_t R = rngs.size();
  std::vector<float> curves(R * size_t(epochs), 0.f);
  std::vector<std::vector<int32_t>> order(R);
  std::vector<const int32_t*> rows(R);
  std::vector<double> sum(R);
  const int first = n > 0 ? epochs_detail::resume_models(resume, epochs, curves, rngs) : 0;
  for (int e = first; e < epochs && n > 0; ++e) {
    for (size_t m = 0; m < R; ++m) shuffle_order(n, rngs[m], order[m]);
    std::fill(sum.begin(), sum.end(), 0.0);
    for (int64_t i0 = 0; i0 < n; i0 += batch) {
      const int b = int(n - i0 < batch ? n - i0 : batch);
      for (size_t m = 0; m < R; ++m) rows[m] = order[m].data() + i0;
      const std::vector<float>& losses = step(rows, b);
      for (size_t m = 0; m < R; ++m) sum[m] += double(losses[m]) * b;
    }
    for (size_t m = 0; m < R; ++m) curves[m * epochs + e] = float(sum[m] / double(n));
    if (epochs_detail::due(resume, e + 1, epochs))
      epochs_detail::save_models(resume, e + 1, curves, rngs);
  }
  return curves;
}

// The training run_epochs_batched runs, in another order: each model runs a stretch of epochs on
// its own before the next model does (the models split over `threads`). Training 20 TPA heads side
// by side streams every head's weights and Adam moments from memory each step (a JacoRobot head
// with its copy of φ is 50 MB); one model's steps in a row find more of them in cache. The models
// are independent (each its own order stream, weights, moments and examples), so every model's
// bits and the curves are run_epochs_batched's.
// step(m, rows, b, t) trains model m on rows[0..b) as its t-th optimizer step (1-based, counted
// from the start of training) and returns its loss. at_epoch(e) is called whenever every model
// that still trains stands at the end of epoch e (before a checkpoint is asked for, and at the
// end), for the caller to bring its own state there.
// Stretches: whole epochs, enough for ≥ `stretch_steps` steps of a model in a row. Checkpoints are
// asked for after each (every model at the same epoch or stopped before it), so a stretch is also
// what a crash can lose. Only the speed and the spacing of checkpoints depend on it, never the
// result.
// Stopping (`stop`, engine/convergence.h): each model is asked after each of its epochs whether
// its own curve so far has converged; a model that stops takes no further step (its FLOPs are not
// spent) and its curve is NaN from there on. A model's stop depends on its own curve only, so the
// result is the same for any thread count, stretch or resume.
// An exception from `step` (out of memory, say) ends the stretch and is rethrown here, before any
// checkpoint (for_each_model).
struct ModelLoopOptions {
  const ResumableState* resume = nullptr;
  int stretch_steps = kStretchSteps;
  StopRule stop;  // fixed (every epoch) unless stop.converged
};
struct ModelCurves {
  std::vector<float> curves;    // [R, epochs]: each epoch's mean loss; NaN after a model stopped
  std::vector<int> epochs_run;  // [R] epochs each model trained (== epochs unless it stopped)
};
template <typename Step, typename AtEpoch>
ModelCurves run_epochs_model_by_model(int64_t n, int epochs, int batch, std::vector<Rng>& rngs,
                                      int threads, Step&& step, AtEpoch&& at_epoch,
                                      const ModelLoopOptions& opt = {}) {
  const int R = int(rngs.size());
  ModelCurves out;
  out.curves.assign(size_t(R) * size_t(epochs), 0.f);
  out.epochs_run.assign(size_t(R), n > 0 ? epochs : 0);
  if (n <= 0) return out;
  const int64_t per_epoch = (n + batch - 1) / batch;
  out.epochs_run.assign(size_t(R), 0);
  std::vector<char> stopped(size_t(R), 0);
  const int first =
      epochs_detail::resume_models(opt.resume, epochs, out.curves, rngs, &out.epochs_run, &stopped);
  const int stretch =
      int(std::max<int64_t>(1, (std::max(1, opt.stretch_steps) + per_epoch - 1) / per_epoch));
  for (int e0 = first; e0 < epochs; e0 += stretch) {
    const int e1 = std::min(epochs, e0 + stretch);
    if (std::all_of(stopped.begin(), stopped.end(), [](char x) { return x != 0; })) break;
    for_each_model(R, threads, [&](int m) {
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
        if (e + 1 < epochs && stops_after(opt.stop, curve, e + 1)) {
          stopped[m] = 1;
          std::fill(curve + e + 1, curve + epochs, std::numeric_limits<float>::quiet_NaN());
          break;
        }
      }
    });
    at_epoch(e1);
    if (epochs_detail::due(opt.resume, e1, epochs))
      epochs_detail::save_models(opt.resume, e1, out.curves, rngs, &out.epochs_run, &stopped);
  }
  return out;
}

}  // namespace sirl
