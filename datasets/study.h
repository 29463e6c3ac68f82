// The user study (paper §5): participants, the queries each is shown, and their answers.
// Plain data shared by the web server, the simulator, the importer and the analysis. The
// trajectory space is regenerated from (env, trajectories, data_seed), so a study file stores
// row ids only and stays small enough to rewrite atomically after every answer.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "datasets/dataset.h"
#include "datasets/simulated_human.h"

namespace sirl {

struct StudyParticipant {
  std::string id, token;                       // token: the secret in the participant's URL
  std::string scenario;                        // the preference scenario shown in phase 2
  std::vector<std::string> scenario_features;  // features that scenario's preference involves
  std::vector<float> reward;                   // simulated participants: true weights [F]
  std::vector<int32_t> similarity;             // [n, 3] rows of Ξ
  std::vector<int32_t> preference;             // [m, 2] rows of Ξ
  // Answers, in query order (a query is answered only after all before it).
  std::vector<int32_t> similarity_answer;           // position (0, 1, 2) of the odd one out
  std::vector<float> preference_answer;             // 1 = first preferred, 0 = second, 0.5 = equal
  std::vector<float> similarity_ms, preference_ms;  // time to answer
  std::vector<double> similarity_time, preference_time;  // when committed (unix seconds)
  int64_t similarity_count() const { return int64_t(similarity.size() / 3); }
  int64_t preference_count() const { return int64_t(preference.size() / 2); }
  int64_t similarity_done() const { return int64_t(similarity_answer.size()); }
  int64_t preference_done() const { return int64_t(preference_answer.size()); }
};

struct Study {
  std::string env = "jaco2";  // an environment with in_study (datasets/environments.h)
  // For an environment read from a file: its data description (the file's XXH3, group and
  // streams), so the study is never analysed against another file under the same name.
  std::string env_data;
  int64_t trajectories = 1000;
  uint64_t data_seed = 0;
  std::vector<StudyParticipant> participants;
  const StudyParticipant* find(const std::string& id) const;
  StudyParticipant* find(const std::string& id);
};

// The study's trajectory space (deterministic). Throws std::invalid_argument for a bad env: one
// not registered (an environment from a file needs the profile that declares it), one the study
// cannot run on, or a file environment whose file is not the one the study was collected on.
Dataset study_dataset(const Study& s);
// A new study's header on `env` (for an environment read from a file, its data description and
// the file's trajectory count). Throws std::invalid_argument as study_dataset does.
Study new_study(const std::string& env, int64_t trajectories, uint64_t data_seed);
// The environments the study may run on, for messages: "grid or jaco2".
std::string study_env_names();

// A participant's queries: n similarity triplets and m preference pairs of distinct rows, from
// the stream seed_from_key("study/" + id, seed). The token is random unless given.
StudyParticipant plan_participant(const Dataset& d, const std::string& id, int64_t n_similarity,
                                  int64_t n_preference, uint64_t seed);

// Answers every open query as a simulated participant would: similarity from `t` over the
// perceived features, preference under p.reward (which must be set). Response times are drawn
// log-normally around 4 s; timestamps are left 0.
void simulate_answers(const Dataset& d, StudyParticipant& p, const Teacher& t, Rng& rng);

// A cohort of simulated novices (the reproduction's stand-in for the paper's 10 participants):
// noisy teachers (Boltzmann β on the normalised features, mistakes), each with a preference
// scenario: 3 in 5 care about every feature, the others about one (6 of the paper's 10
// participants had preferences involving both features).
struct CohortConfig {
  std::string env = "jaco2";
  int64_t trajectories = 1000;
  int users = 10;
  int64_t similarity = 100, preference = 100;  // answered queries per participant
  double beta = 20, mistake = 0.05;
  uint64_t seed = 0;  // the trajectory space's and the cohort's
};
// The participant ids simulate_cohort gives: "sim01", "sim02", …
std::string simulated_participant_id(int u);
// The cohort's study (env, Ξ's size and seed, every participant's answers). Deterministic.
// Throws std::invalid_argument for a bad environment or teacher.
Study simulate_cohort(const CohortConfig& c);

// Pooled similarity answers of `participants` as (positive 1, positive 2, negative) row triplets.
std::vector<int32_t> answered_triplets(const std::vector<const StudyParticipant*>& participants);

// Participant ids and tokens: [A-Za-z0-9_-]{1,64}. Throws std::invalid_argument otherwise.
void validate_participant_id(const std::string& id);
// A fresh participant token: 32 hex digits (128 bits) from the OS's random device.
std::string new_participant_token();

}  // namespace sirl
