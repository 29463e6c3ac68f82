#include "experiment/expected_epochs.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace sirl {

namespace {

// A measured median at one query count (N triplets for SIRL, M pairs for the heads).
struct Point {
  int64_t queries;
  double epochs;
};

// Linear in log(queries) between measured points, the nearest point's value outside them.
double interpolate(const std::vector<Point>& pts, int64_t q) {
  if (pts.empty()) return INFINITY;
  if (q <= pts.front().queries) return pts.front().epochs;
  if (q >= pts.back().queries) return pts.back().epochs;
  for (size_t i = 1; i < pts.size(); ++i)
    if (q <= pts[i].queries) {
      const double a = std::log(double(pts[i - 1].queries)), b = std::log(double(pts[i].queries));
      const double w = (std::log(double(q)) - a) / (b - a);
      return pts[i - 1].epochs + w * (pts[i].epochs - pts[i - 1].epochs);
    }
  return pts.back().epochs;
}

struct SirlSkip {
  const char* env;
  bool vae_pretrain;
  std::vector<Point> at_N;  // the epoch of the exact skip, median over seeds
};

// Measured with the paper's SIRL hyper-parameters (the runs: docs/stopping-rule.md):
// JacoRobot N = 1000 (bench/sirl-past-zero-loss.toml, seed 0): skipped after epoch 158, the
// same point for every N until other N are measured.
const std::vector<SirlSkip>& sirl_skips() {
  static const std::vector<SirlSkip> t = {
      {"jaco", false, {{1000, 158}}},
  };
  return t;
}

struct HeadStops {
  const char* env;
  bool frozen;
  std::vector<Point> at_M;  // mean epochs a head runs under the default rule, median over cells
};

// Measured under the default rule (the runs: docs/stopping-rule.md), every cell at N = 1000:
// JacoRobot seeds 0-2, SIRL frozen and Random / SinglePref / MultiPref-10 unfrozen at M = 10 and
// 50 (bench/stop-equivalence-jaco.toml); GridRobot seeds 0-9, every method in its best mode at
// M = 10, 50, 100 and 190 (bench/stop-equivalence-grid.toml). Every head stopped at the rule's
// minimum, 100 epochs, but a few of SIRL's on JacoRobot at M = 10; larger M, whose losses
// flatten sooner, are taken to stop there too.
const std::vector<HeadStops>& head_stops() {
  static const std::vector<HeadStops> t = {
      {"jaco", true, {{10, 101.6}, {50, 100}}},
      {"jaco", false, {{10, 100}, {50, 100}}},
      {"grid", true, {{10, 100}, {190, 100}}},
      {"grid", false, {{10, 100}, {190, 100}}},
  };
  return t;
}

}  // namespace

double expected_sirl_epochs(const std::string& env, int64_t N, bool vae_pretrain, const Hyper& h) {
  for (const auto& s : sirl_skips())
    if (env == s.env && vae_pretrain == s.vae_pretrain)
      return std::min(double(h.sirl.epochs), interpolate(s.at_N, N));
  return h.sirl.epochs;
}

double expected_head_epochs(const std::string& env, bool frozen, int64_t M, const Hyper& h) {
  const StopRule rule = tpa_stop_rule(h, frozen);
  // Measured under the default rule only: another minimum or tolerance stops elsewhere.
  const StopRule standard{true};
  if (!rule.converged || rule.min_epochs != standard.min_epochs || rule.rel_tol != standard.rel_tol)
    return h.tpa.epochs;
  for (const auto& s : head_stops())
    if (env == s.env && frozen == s.frozen)
      return std::min(double(h.tpa.epochs),
                      std::max(double(rule.min_epochs), interpolate(s.at_M, M)));
  return h.tpa.epochs;
}

}  // namespace sirl
