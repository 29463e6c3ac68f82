// SIRL (paper §4.1): φ trained with the symmetric triplet loss on the first N similarity answers.
#include <algorithm>
#include <vector>

#include "datasets/query_bundle.h"
#include "engine/epochs.h"
#include "engine/method_trainers.h"
#include "engine/methods.h"
#include "engine/train_step.h"
#include "kernels/rng.h"
#include "kernels/triplet_loss.h"

namespace sirl {

namespace {

// Whether every value is exactly 0.
bool all_zero(const std::vector<float>& v) {
  return std::all_of(v.begin(), v.end(), [](float x) { return x == 0.f; });
}

// SIRL's triplet loss is a hinge: once every triplet is inside its margin, the loss and every
// gradient are exactly 0, Adam's first moments decay to exactly 0 (kernels/adam.h stores a moment
// below the smallest normal float as 0), and from then on every step leaves every weight bit
// unchanged. An epoch that starts with every first moment 0 and whose every triplet stays inside
// its margin by kFixedPointSlack·max(α, 1) therefore ends where it began, and so does every epoch
// after it: training skips to its end (run_epochs' at_fixed_point; the skipped epochs' loss is 0,
// as the full run's). The slack keeps the decision clear of rounding: a triplet's hinge is
// computed from its rows' embeddings, which another batch of the next epoch might round
// differently in the last bits.
constexpr float kFixedPointSlack = 1e-3f;

}  // namespace

void train_sirl(const Dataset& d, const QueryBundle& bundle, const MethodConfig& cfg, uint64_t seed,
                const Execution& ex, Representation& rep) {
  const TripletSet q = first_triplets(bundle.similarity, cfg.queries);
  const TrainSchedule& s = cfg.hyper.sirl;
  Trainer t(rep.shape, s.adam, rep.params);
  Rng order_rng(seed_from_key("sirl_order", seed));
  std::vector<int32_t> batch;
  const ResumableState resume =
      adam_resumable(ex.checkpointer, "sirl", t.params, t.adam, rep.train_flops);
  const float margin = float(cfg.hyper.triplet_margin);
  const float inside = -kFixedPointSlack * std::max(margin, 1.f);
  // Per epoch: whether it started with every first moment 0, and whether every triplet so far
  // was inside its margin by the slack.
  bool epoch_start = true, moments_zero = false, idle = false;
  const double epoch_flops = epoch_train_flops(t.shape, q.count, s.batch, 3);  // every epoch's
  int skipped = 0;
  rep.loss_curve = run_epochs(
      q.count, s.epochs, s.batch, order_rng,
      [&](const int32_t* rows, int b) {
        if (epoch_start) {
          moments_zero = all_zero(t.adam.m);  // after a resume too: the restored moments
          idle = true;
          epoch_start = false;
        }
        batch.resize(size_t(3) * b);
        for (int i = 0; i < b; ++i)
          std::copy_n(q.idx.begin() + 3 * rows[i], 3, batch.begin() + 3 * i);
        rep.train_flops += t.shape.train_flops(3 * b);
        const float loss = triplet_train_step(t, 0, adam_begin_step(s.adam, t.adam),
                                              d.inputs.data(), batch.data(), b, margin, ex.threads);
        if (idle)
          idle = triplet_max_hinge(t.work[0].tape.output(), b, t.shape.out(), margin) <= inside;
        return loss;
      },
      &resume,
      [&](int done) {
        epoch_start = true;
        if (!(cfg.skip_fixed_point && moments_zero && idle)) return false;
        skipped = s.epochs - done;
        return true;
      });
  rep.skipped_flops = skipped * epoch_flops;
  rep.params = std::move(t.params);
}

}  // namespace sirl
