// When has a training converged? One definition for every training in sirl-bench (SIRL, the
// preference pre-training, the VAE, the TPA heads), recorded with every task and printed in the
// report:
//   a = mean loss over the second-to-last 10 % of the epochs, b = mean over the last 10 %
//   converged  ⇔  |a − b| ≤ rel_tol · max(|a|, |b|) + abs_tol
// i.e. the loss changed by less than 1 % (default) over the last tenth of the training. Means
// over windows, not single epochs, so mini-batch noise does not decide it. Fewer than 20 epochs
// give windows of one epoch; fewer than 2 epochs cannot be judged (converged = false).
#pragma once
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
