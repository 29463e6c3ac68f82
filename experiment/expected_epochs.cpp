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
  double rel_tol;           // the rule's tolerance for these cells (tpa.stop[_frozen]_rel_tol)
  std::vector<Point> at_M;  // mean epochs a head runs, median over cells
};

// Measured with the rule's minimum of 100 epochs (the runs: docs/stopping-rule.md), every cell
// at N = 1000:
// - tolerance 0.01: JacoRobot seeds 0-2, SIRL frozen and Random / SinglePref / MultiPref-10
//   unfrozen at M = 10 and 50 (bench/stop-equivalence-jaco.toml); GridRobot seeds 0-9, every
//   method in its best mode at M = 10, 50, 100 and 190 (bench/stop-equivalence-grid.toml). Every
//   head stopped at the minimum, 100 epochs, but a few of SIRL's on JacoRobot at M = 10; larger
//   M, whose losses flatten sooner, are taken to stop there too.
// - tolerance 0.001, JacoRobot frozen: the rule applied to every frozen head's curve of
//   configs/jaco-fig5.toml run at the paper's 1000 epochs (SIRL and SIRL+VAE, seeds 0-2, M = 10,
//   50, 100, 190; a head stopped after k epochs is that run's head at k, so its curve up to k is
//   the stopped head's).
const std::vector<HeadStops>& head_stops() {
  static const std::vector<HeadStops> t = {
      {"jaco", true, 0.01, {{10, 101.6}, {50, 100}}},
      {"jaco", false, 0.01, {{10, 100}, {50, 100}}},
      {"jaco", true, 0.001, {{10, 367.9}, {50, 742.6}, {100, 597.3}, {190, 533.5}}},
      {"grid", true, 0.01, {{10, 100}, {190, 100}}},
      {"grid", false, 0.01, {{10, 100}, {190, 100}}},
  };
  return t;
}

struct PrefStops {
  const char* env;
  const char* method;
  bool vae_pretrain;
  int min_epochs;           // the rule's pref.stop_min_epochs and pref.stop_rel_tol they were
  double rel_tol;           // measured at
  std::vector<Point> at_N;  // the stopping epoch, median over seeds
};

// Measured with the rule's minimum of 500 epochs and tolerance 0.01 (the run:
// docs/stopping-rule.md, "Preference φ that stop when they have learned"; its report
// docs/stop-equivalence/jaco-pref.md): JacoRobot seeds 0-2 at N = 1000, without VAE pre-training.
// All nine φ stopped at the minimum; other N are taken to stop there too until they are measured.
// (The test did not show the rule equivalent, so no shipped profile stops these φ: this table
// serves a profile that opts in.)
const std::vector<PrefStops>& pref_stops() {
  static const std::vector<PrefStops> t = {
      {"jaco", "singlepref", false, 500, 0.01, {{1000, 500}}},
      {"jaco", "multipref10", false, 500, 0.01, {{1000, 500}}},
      {"jaco", "multipref50", false, 500, 0.01, {{1000, 500}}},
  };
  return t;
}

}  // namespace

double expected_pref_epochs(const std::string& env, const std::string& method, int64_t N,
                            bool vae_pretrain, const Hyper& h) {
  if (h.pref_stop != "converged") return h.pref.epochs;
  for (const auto& s : pref_stops())
    if (env == s.env && method == s.method && vae_pretrain == s.vae_pretrain &&
        h.pref_stop_min_epochs == s.min_epochs && h.pref_stop_rel_tol == s.rel_tol)
      return std::min(double(h.pref.epochs),
                      std::max(double(s.min_epochs), interpolate(s.at_N, N)));
  return h.pref.epochs;
}

double expected_sirl_epochs(const std::string& env, int64_t N, bool vae_pretrain, const Hyper& h) {
  for (const auto& s : sirl_skips())
    if (env == s.env && vae_pretrain == s.vae_pretrain)
      return std::min(double(h.sirl.epochs), interpolate(s.at_N, N));
  return h.sirl.epochs;
}

double expected_head_epochs(const std::string& env, bool frozen, int64_t M, const Hyper& h) {
  const StopRule rule = tpa_stop_rule(h, frozen);
  // Measured at the default minimum and the tolerances above only: others stop elsewhere.
  if (!rule.converged || rule.min_epochs != StopRule{}.min_epochs) return h.tpa.epochs;
  for (const auto& s : head_stops())
    if (env == s.env && frozen == s.frozen && rule.rel_tol == s.rel_tol)
      return std::min(double(h.tpa.epochs),
                      std::max(double(rule.min_epochs), interpolate(s.at_M, M)));
  return h.tpa.epochs;
}

}  // namespace sirl
