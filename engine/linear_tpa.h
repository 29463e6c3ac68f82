// TPA under linear evaluation: the standard linear-evaluation protocol of representation learning
// beside the paper's reward head (engine/tpa.h). For each test reward, a linear Bradley–Terry
// head on the frozen φ, standardised (kernels/linear_bradley_terry.h): L2-regularised logistic
// regression on the same first M training pairs, its penalty chosen by cross-validation on those
// M pairs only, fit to convergence by Newton's method, and scored on the same held-out pairs.
// Nothing is drawn at random: the result is a function of φ and the pairs.
#pragma once
#include <cstdint>
#include <vector>

#include "datasets/dataset.h"
#include "datasets/queries.h"
#include "engine/representation.h"
#include "kernels/linear_bradley_terry.h"

namespace sirl {

struct LinearTpaResult {
  std::vector<double> accuracy;        // [R] held-out accuracy per test reward
  std::vector<double> train_accuracy;  // [R] accuracy on its own M training pairs
  std::vector<int> iterations;         // [R] Newton steps of each head
  std::vector<int> rank;               // [R] dimension of the span its fit ran in
  std::vector<double> alpha;           // [R] the penalty cross-validation chose
  double mean = 0, stddev = 0;         // TPA = mean over rewards; stddev over rewards (n − 1)
  bool converged = true;               // every head's fit converged
  double flops = 0;
};

// sets[r] as evaluate_tpa reads them: rows [0, train) train (the first M used), [train, count)
// held out. Throws std::invalid_argument if M is outside [1, train] or a held-out split is empty,
// and std::runtime_error if φ(ξ) is not finite.
LinearTpaResult evaluate_linear_tpa(const Representation& rep, const Dataset& d,
                                    const std::vector<TpaSet>& sets, int64_t M,
                                    const LinearBtOptions& options, int threads = 1);

}  // namespace sirl
