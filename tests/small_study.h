// A simulated GridRobot study cohort for the study tests: user u's reward is feature u mod F,
// answered by a Boltzmann teacher with the given rationality and mistake rate (seeded: fixed).
#pragma once

#include <string>
#include <utility>

#include "datasets/simulated_human.h"
#include "datasets/study.h"
#include "kernels/rng.h"

namespace sirl::test {

inline Study simulated_cohort(int users, double beta, double mistake) {
  Study s;
  s.env = "grid";
  const Dataset d = study_dataset(s);
  Teacher t;
  t.beta = beta;
  t.mistake = mistake;
  Rng rng(3);
  for (int u = 0; u < users; ++u) {
    StudyParticipant p = plan_participant(d, "u" + std::to_string(u), 100, 60, 1);
    p.reward.assign(d.feature_count(), 0.f);
    p.reward[u % d.feature_count()] = 1.f;
    p.scenario_features = {d.feature_names[u % d.feature_count()]};
    simulate_answers(d, p, t, rng);
    s.participants.push_back(std::move(p));
  }
  return s;
}

}  // namespace sirl::test
