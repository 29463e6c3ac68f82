// The user study's analysis (paper §5): SIRL trained on the pooled similarity answers against a
// Random representation — FPE per training seed; TPA "Real" (each participant's own preference
// answers, 70/30 cross-validation splits), "Held-out" (SIRL trained without that participant's
// similarity answers), "Simulated" (perfect preference queries for random rewards). The numbers
// only: the statistics (t-test, ANOVAs) and Fig. 6 are drawn from them by results/plot_study.py.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "datasets/study.h"
#include "engine/hyperparams.h"

namespace sirl {

struct StudyAnalysisConfig {
  int seeds = 5;       // SIRL / Random training seeds for FPE
  int cv_splits = 50;  // random 70/30 splits of each participant's preferences
  double train_fraction = 0.7;
  int simulated_rewards = 10;
  int simulated_queries = 100;  // per reward (70 train / 30 test)
  int64_t fpe_trajectories = 1000;
  Hyper hyper;  // the environment's; sirl.* and tpa.* are used
  uint64_t seed = 0;
  int threads = 1;
  // SIRL is evaluated frozen (its best mode, Fig. 5). Random is evaluated both ways; which one
  // is "Random" in H4 is this switch: unfrozen by default, as the paper's "best performing
  // realistic baseline" is in its Fig. 5 (φ and the head trained together per split).
  bool random_frozen = false;
  // Called after each participant's TPA (done of total), e.g. to print progress with an ETA.
  std::function<void(int done, int total)> progress;
};

struct StudyAnalysis {
  int64_t triplets = 0;                                  // pooled similarity answers
  std::vector<double> fpe_sirl, fpe_random;              // [seeds]
  std::vector<std::string> participants;                 // [P] those with preference answers
  std::vector<uint8_t> both_features;                    // [P] scenario involves every feature
  std::vector<double> real_sirl, real_random;            // [P] mean TPA over the CV splits
  std::vector<double> heldout_sirl, heldout_random;      // [P]
  std::vector<double> simulated_sirl, simulated_random;  // [rewards]
  // Random in the other mode than random_frozen picks (reported beside it).
  std::vector<double> real_random_other, heldout_random_other, simulated_random_other;
};

// Throws std::invalid_argument when there are no similarity answers to train on.
StudyAnalysis analyze_study(const Study& s, const Dataset& d, const StudyAnalysisConfig& c);

}  // namespace sirl
