// When has a training converged? One definition for every training in sirl-bench (SIRL, the
// preference pre-training, the VAE, the TPA heads), recorded with every task and printed in the
// report:
//   a = mean loss over the second-to-last 10 % of the epochs, b = mean over the last 10 %
//   converged  ⇔  |a − b| ≤ rel_tol · max(|a|, |b|) + abs_tol
// i.e. the loss changed by less than 1 % (default) over the last tenth of the training. Means
// over windows, not single epochs, so mini-batch noise does not decide it. Fewer than 20 epochs
// give windows of one epoch; fewer than 2 epochs cannot be judged (converged = false).
#pragma once
#include <string>
#include <string_view>
#include <vector>

namespace sirl {

struct Convergence {
  bool converged = false;
  double relative_change = 0;  // (a − b) / max(|a|, |b|): > 0 while the loss still falls
  int window = 0;              // epochs per window (0: too few epochs to judge)
};

inline constexpr double kConvergenceRelTol = 0.01;
inline constexpr double kConvergenceAbsTol = 1e-4;

Convergence check_convergence(const std::vector<float>& curve, double rel_tol = kConvergenceRelTol,
                              double abs_tol = kConvergenceAbsTol);

}  // namespace sirl

namespace sirl {

// When a reward head's training ends (tpa.stop): `fixed` runs every epoch of the schedule (the
// paper's protocol); `converged` ends a head at the first epoch e ≥ min_epochs at which its loss
// curve so far, curve[0, e), satisfies check_convergence with rel_tol (the loss moved by less
// than rel_tol over the last tenth of the epochs run), and never later than the schedule's
// epochs. Only the head's own training loss decides: never held-out pairs or accuracy, so the
// rule cannot be tuned to the verdicts it produces.
struct StopRule {
  bool converged = false;  // false: fixed
  int min_epochs = 100;
  double rel_tol = kConvergenceRelTol;
};

// Whether a head whose curve so far is curve[0, e) stops after epoch e under `rule`.
bool stops_after(const StopRule& rule, const float* curve, int e);

// The reward heads' stop rules (the values of tpa.stop), each declared once: its name, the cells
// whose heads it may end early (by StopRule, at that mode's tolerance) and what it does. The
// hyper-parameters' check, tpa_stop_rule and `sirl plan` read these entries; a new rule over
// the same StopRule is one entry.
struct TpaStopRule {
  const char* name;
  bool stops_unfrozen, stops_frozen;
  const char* doc;
};
inline constexpr TpaStopRule kTpaStopRules[] = {
    {"fixed", false, false, "every epoch, the paper's"},
    {"converged", true, true, "each head stops once its loss has converged"},
    {"converged-unfrozen", true, false, "only unfrozen cells' heads stop early"},
};
// The entry named `name`; nullptr when there is none.
const TpaStopRule* find_tpa_stop_rule(std::string_view name);
// Whether rule `name` may end any head early (false for "fixed" and for unknown names).
bool tpa_stop_may_end_early(std::string_view name);
// Every rule for messages: "\"fixed\" (every epoch, the paper's), … or \"converged-unfrozen\" (…)".
std::string tpa_stop_rule_list();

}  // namespace sirl
