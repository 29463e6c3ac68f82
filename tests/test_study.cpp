// The user study's participants: planned queries, simulated answers, participant ids.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "datasets/study.h"
#include "kernels/rng.h"

namespace sirl {
namespace {

TEST(Study, AnsweredTripletsPutTheOddOneOutLast) {
  StudyParticipant p;
  p.similarity = {10, 11, 12, 20, 21, 22};
  p.similarity_answer = {0, 2};  // odd one out: 10, then 22
  const auto t = answered_triplets({&p});
  EXPECT_EQ(t, (std::vector<int32_t>{11, 12, 10, 20, 21, 22}));
}

TEST(Study, SimulatedAnswersFollowTheTeacher) {
  Study s;
  s.env = "grid";
  const Dataset d = study_dataset(s);
  StudyParticipant p = plan_participant(d, "perfect", 50, 50, 2);
  p.reward.assign(d.feature_count(), 0.f);
  p.reward[0] = 1.f;
  Rng rng(1);
  simulate_answers(d, p, Teacher{}, rng);
  ASSERT_EQ(p.preference_done(), 50);
  for (int64_t i = 0; i < 50; ++i) {
    const double ra = reward(p.reward.data(), d.feature(p.preference[2 * i]), d.feature_count());
    const double rb =
        reward(p.reward.data(), d.feature(p.preference[2 * i + 1]), d.feature_count());
    if (ra != rb) {
      EXPECT_EQ(p.preference_answer[i], ra > rb ? 1.f : 0.f);
    }
  }
  for (int64_t i = 0; i < 50; ++i) {  // the odd one out is the farthest from the closest pair
    const int32_t* q = p.similarity.data() + 3 * i;
    auto dist = [&](int a, int b) {
      double s2 = 0;
      for (int k = 0; k < d.feature_count(); ++k)
        s2 += std::pow(d.feature(q[a])[k] - d.feature(q[b])[k], 2);
      return s2;
    };
    const int neg = p.similarity_answer[i];
    EXPECT_LE(dist((neg + 1) % 3, (neg + 2) % 3),
              std::min(dist(neg, (neg + 1) % 3), dist(neg, (neg + 2) % 3)));
  }
}

TEST(Study, ParticipantIdsAreChecked) {
  EXPECT_NO_THROW(validate_participant_id("P-07_a"));
  EXPECT_THROW(validate_participant_id(""), std::invalid_argument);
  EXPECT_THROW(validate_participant_id("../etc"), std::invalid_argument);
  EXPECT_THROW(validate_participant_id(std::string(65, 'a')), std::invalid_argument);
}

}  // namespace
}  // namespace sirl
