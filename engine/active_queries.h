// Active selection of similarity queries — beyond the paper, which samples its triplets
// uniformly (its future work asks which queries a robot should ask). In rounds:
//   1. train an ensemble of K φ (own initialisations and batch orders, warm-started across
//      rounds) on the triplets answered so far;
//   2. draw a pool of candidate triplets uniformly from Ξ (never one asked before);
//   3. score each by how much the members disagree about its odd one out;
//   4. ask the teacher the best `batch` of them, no trajectory twice in one batch (diversity);
// until the budget is spent. The first round asks a uniform batch (nothing to disagree on yet).
// Two scores:
//   vote      vote entropy of the members' hard answers (Seung et al.'s query by committee);
//   infogain  the crowd-kernel rule (Tamuz et al. 2011): expected information gain about the
//             embedding under the probabilistic triplet model P(pair k) ∝ 1/(μ + d_k), the
//             posterior approximated by the ensemble — i.e. the mutual information between the
//             answer and the member (BALD).
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "datasets/dataset.h"
#include "datasets/queries.h"
#include "datasets/simulated_human.h"
#include "engine/checkpoint.h"
#include "engine/execution.h"
#include "engine/hyperparams.h"
#include "engine/selection.h"

namespace sirl {

// How the ensemble asks, round by round: a profile's [active] table (defaults measured in
// docs/active.md).
struct ActiveRounds {
  int members = 5;        // K, the ensemble
  int64_t pool = 8000;    // candidate triplets drawn per round
  int64_t batch = 100;    // triplets asked per round
  int round_epochs = 50;  // epochs each member trains per round (warm start)
  double mu = 0.05;       // crowd-kernel μ, in units of the member's median pair distance
};

struct ActiveConfig : ActiveRounds {
  Selection rule = Selection::vote;
  int64_t budget = 1000;  // triplets asked in all (the largest N of the cells that read them)
  Hyper hyper;            // φ's shape and the SIRL schedule's batch, Adam and margin
};

struct ActiveQueries {
  TripletSet queries;              // [budget, 3] (P1, P2, N) in the order asked: nested in N
  std::vector<float> batch_score;  // per round: mean score of the triplets it asked (0: round 0)
  std::vector<float> pool_score;   // per round: mean score over its pool
  int rounds = 0;
  double train_flops = 0;  // the ensemble's training and its passes over the pools
};

// Throws std::invalid_argument for a config that cannot work (K < 2, batch < 1, pool < batch,
// budget above what Ξ can offer) and std::runtime_error if the members diverge.
ActiveQueries select_active_queries(const Dataset& d, const Teacher& teacher,
                                    const ActiveConfig& cfg, uint64_t seed,
                                    const Execution& ex = {});  // checkpoints after rounds

// ---- the scores (nats) ----
// Pairs are numbered as the simulated human does: 0 = (1,2 | 3), 1 = (1,3 | 2), 2 = (2,3 | 1).

// votes [K] ∈ {0, 1, 2}: entropy of the vote shares. 0 when all agree; log 3 when three members
// vote three ways.
double vote_entropy(const int* votes, int K);
// probs [K, 3], rows summing to 1: H(mean row) − mean H(row), ≥ 0; 0 when the rows agree.
double mutual_information(const double* probs, int K);
// d [3] pair distances: P(pair k is the closest) ∝ 1/(μ + d_k) (for two options Tamuz et al.'s
// (μ + δ_ac)/(2μ + δ_ab + δ_ac)).
std::array<double, 3> crowd_kernel_probs(const std::array<double, 3>& d, double mu);

}  // namespace sirl
