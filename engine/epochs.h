// Mini-batch order for one epoch, as PyTorch's DataLoader(shuffle=True, drop_last=False):
// a fresh permutation of the n examples each epoch, cut into batches of `batch` (the last one
// shorter when batch does not divide n).
#pragma once
#include <algorithm>
#include <cstdint>
#include <numeric>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "engine/checkpoint.h"
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
// R models' loop state: curves [R, epochs] and each model's order stream. Returns the epoch a
// saved state resumes from (0: none).
inline int resume_models(const ResumableState* r, int epochs, std::vector<float>& curves,
                         std::vector<Rng>& rngs) {
  TrainingSnapshot s;
  if (!resume(r, epochs, s)) return 0;
  curves = s.get("loop/curves", curves.size());
  for (size_t m = 0; m < rngs.size(); ++m) s.get_rng("loop/order/" + std::to_string(m), rngs[m]);
  return s.epoch;
}
inline void save_models(const ResumableState* r, int epoch, const std::vector<float>& curves,
                        const std::vector<Rng>& rngs) {
  TrainingSnapshot s;
  s.epoch = epoch;
  s.floats["loop/curves"] = curves;
  for (size_t m = 0; m < rngs.size(); ++m) s.put_rng("loop/order/" + std::to_string(m), rngs[m]);
  save(r, s);
}
}  // namespace epochs_detail

// `epochs` passes over n examples in shuffled mini-batches. step(rows, b) trains on the b example
// indices rows[0..b) and returns that batch's mean loss. Returns each epoch's mean loss.
// With `resume`, a saved state is picked up first and the state is saved after epochs when the
// checkpointer says so; the result is the same bits either way.
template <typename Step>
std::vector<float> run_epochs(int64_t n, int epochs, int batch, Rng& rng, Step&& step,
                              const ResumableState* resume = nullptr) {
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
// with its copy of φ is 50 MB); one model's steps in a row find more of them in cache (a quick
// run's smallest JacoRobot cells ran 1.35–1.4× faster, docs/roofline.md). The models are
// independent (each its own order stream, weights, moments and examples), so every model's bits
// and the curves are run_epochs_batched's.
// step(m, rows, b, t) trains model m on rows[0..b) as its t-th optimizer step (1-based, counted
// from the start of training) and returns its loss. at_epoch(e) is called whenever every model
// stands at the end of epoch e (before a checkpoint is asked for, and at the end), for the caller
// to bring its own state there (e.g. Adam's step count: e · batches per epoch).
// Stretches: whole epochs, enough for ≥ `stretch_steps` steps of a model in a row. Checkpoints are
// asked for after each (every model at the same epoch), so a stretch is also what a crash can
// lose. Only the speed and the spacing of checkpoints depend on it, never the result.
// An exception from `step` (out of memory, say) ends the stretch and is rethrown here, before any
// checkpoint (for_each_model).
inline constexpr int kStretchSteps = 32;
template <typename Step, typename AtEpoch>
std::vector<float> run_epochs_model_by_model(int64_t n, int epochs, int batch,
                                             std::vector<Rng>& rngs, int threads, Step&& step,
                                             AtEpoch&& at_epoch,
                                             const ResumableState* resume = nullptr,
                                             int stretch_steps = kStretchSteps) {
  const int R = int(rngs.size());
  std::vector<float> curves(size_t(R) * size_t(epochs), 0.f);
  if (n <= 0) return curves;
  const int64_t per_epoch = (n + batch - 1) / batch;
  const int first = epochs_detail::resume_models(resume, epochs, curves, rngs);
  const int stretch =
      int(std::max<int64_t>(1, (std::max(1, stretch_steps) + per_epoch - 1) / per_epoch));
  for (int e0 = first; e0 < epochs; e0 += stretch) {
    const int e1 = std::min(epochs, e0 + stretch);
    for_each_model(R, threads, [&](int m) {
      std::vector<int32_t> order;
      for (int e = e0; e < e1; ++e) {
        shuffle_order(n, rngs[m], order);
        double sum = 0;
        for (int64_t i0 = 0; i0 < n; i0 += batch) {
          const int b = int(n - i0 < batch ? n - i0 : batch);
          const int64_t t = int64_t(e) * per_epoch + i0 / batch + 1;
          sum += double(step(m, order.data() + i0, b, t)) * b;
        }
        curves[size_t(m) * epochs + e] = float(sum / double(n));
      }
    });
    at_epoch(e1);
    if (epochs_detail::due(resume, e1, epochs))
      epochs_detail::save_models(resume, e1, curves, rngs);
  }
  return curves;
}

}  // namespace sirl
