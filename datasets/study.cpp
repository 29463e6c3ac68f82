#include "datasets/study.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>

#include "datasets/environments.h"

namespace sirl {

const StudyParticipant* Study::find(const std::string& id) const {
  for (const auto& p : participants)
    if (p.id == id) return &p;
  return nullptr;
}
StudyParticipant* Study::find(const std::string& id) {
  for (auto& p : participants)
    if (p.id == id) return &p;
  return nullptr;
}

namespace {

// "grid, jaco2, driver" (built in) and the file environments the study may run on.
std::string study_env_list() {
  std::string built, files;
  for (const auto& e : environments())
    if (e.in_study) {
      std::string& list = e.from_file ? files : built;
      list += (list.empty() ? "" : ", ") + e.name;
    }
  return "built in: " + built + (files.empty() ? "" : "; declared from files: " + files);
}

const EnvSpec& study_env(const std::string& name) {
  const EnvSpec* e = nullptr;
  for (const auto& spec : environments())
    if (spec.name == name) e = &spec;
  if (!e)
    throw std::invalid_argument("'" + name + "' is not an environment the study can run on (" +
                                study_env_list() +
                                "); an environment from a file needs --profile naming a profile "
                                "that declares [environments." +
                                name + "]");
  if (!e->in_study)
    throw std::invalid_argument(
        "the study cannot run on environment '" + name + "' (" + study_env_list() + ")" +
        (e->from_file ? ": the study page draws a file environment's 2-D points, and its file "
                        "has none (or 3-D ones)"
                      : ""));
  return *e;
}

// The part of a file environment's data description that fixes Ξ: the file's digest and group
// ("file xxh3=… group=…"), not the streams its tasks draw from (a study's queries are stored).
std::string trajectory_set(const std::string& env_data) {
  return env_data.substr(0, std::min(env_data.find(" streams="), env_data.find('\n')));
}

}  // namespace

Dataset study_dataset(const Study& s) {
  const EnvSpec& e = study_env(s.env);
  if (e.from_file) {
    const std::string have = e.describe_data(EnvConfig{});
    if (s.env_data.empty())
      throw std::invalid_argument("the study on '" + s.env +
                                  "' does not record which environment file it was collected on");
    if (trajectory_set(have) != trajectory_set(s.env_data))
      throw std::invalid_argument("the study on '" + s.env + "' was collected on " +
                                  trajectory_set(s.env_data) + ", the profile declares " +
                                  trajectory_set(have) + ": not the same trajectories");
  }
  EnvConfig c;
  if (e.set_sample) e.set_sample(c, s.trajectories, s.data_seed);
  return e.make(c);
}

Study new_study(const std::string& env, int64_t trajectories, uint64_t data_seed) {
  const EnvSpec& e = study_env(env);
  Study s;
  s.env = env;
  s.data_seed = data_seed;
  s.trajectories = trajectories;
  if (e.from_file) {  // a file's Ξ is what it holds
    s.trajectories = e.trajectories(EnvConfig{});
    s.env_data = e.describe_data(EnvConfig{});
  }
  return s;
}

std::string study_env_names() {
  std::string names;
  for (const auto& e : environments())
    if (e.in_study) names += (names.empty() ? "" : " or ") + e.name;
  return names;
}

void validate_participant_id(const std::string& id) {
  bool ok = !id.empty() && id.size() <= 64;
  for (char c : id)
    ok = ok && (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-');
  if (!ok)
    throw std::invalid_argument("participant id '" + id +
                                "' must be 1-64 characters of A-Z, a-z, 0-9, _ or -");
}

StudyParticipant plan_participant(const Dataset& d, const std::string& id, int64_t n_sim,
                                  int64_t n_pref, uint64_t seed) {
  validate_participant_id(id);
  if (n_sim < 0 || n_pref < 0) throw std::invalid_argument("query counts must be >= 0");
  if (d.count < 3) throw std::invalid_argument("the study needs at least 3 trajectories");
  StudyParticipant p;
  p.id = id;
  Rng rng(seed_from_key("study/" + id, seed));
  auto distinct = [&](int k, int32_t* out) {
    for (int i = 0; i < k; ++i) {
      bool again;
      do {
        out[i] = int32_t(rng.uniform_int(uint64_t(d.count)));
        again = false;
        for (int j = 0; j < i; ++j) again |= out[j] == out[i];
      } while (again);
    }
  };
  p.similarity.resize(size_t(3 * n_sim));
  for (int64_t i = 0; i < n_sim; ++i) distinct(3, p.similarity.data() + 3 * i);
  p.preference.resize(size_t(2 * n_pref));
  for (int64_t i = 0; i < n_pref; ++i) distinct(2, p.preference.data() + 2 * i);
  p.token = new_participant_token();
  return p;
}

std::string new_participant_token() {
  // A capability, not a key: 128 bits from the OS, never from a study seed.
  std::random_device rd;
  static const char* hex = "0123456789abcdef";
  std::string token;
  for (int i = 0; i < 32; ++i) token += hex[rd() % 16];
  return token;
}

void simulate_answers(const Dataset& d, StudyParticipant& p, const Teacher& t, Rng& rng) {
  const int F = d.feature_count();
  if (int(p.reward.size()) != F)
    throw std::invalid_argument("simulated participant " + p.id + " has no reward over the " +
                                std::to_string(F) + " features");
  auto ms = [&] { return float(4000.0 * std::exp(0.5 * rng.normal())); };
  for (int64_t i = p.similarity_done(); i < p.similarity_count(); ++i) {
    const int32_t* q = p.similarity.data() + 3 * i;
    std::optional<TripletAnswer> a;
    while (!(a = answer_similarity(t, d.feature(q[0]), d.feature(q[1]), d.feature(q[2]), F, rng)))
      ;  // a simulated participant in a study must answer: re-ask until the teacher does
    p.similarity_answer.push_back(a->neg);
    p.similarity_ms.push_back(ms());
    p.similarity_time.push_back(0);
  }
  Teacher answering = t;
  answering.skip = 0;  // same reason
  for (int64_t i = p.preference_done(); i < p.preference_count(); ++i) {
    const int32_t* q = p.preference.data() + 2 * i;
    p.preference_answer.push_back(
        *answer_preference(answering, p.reward.data(), d.feature(q[0]), d.feature(q[1]), F, rng));
    p.preference_ms.push_back(ms());
    p.preference_time.push_back(0);
  }
}

std::vector<int32_t> answered_triplets(const std::vector<const StudyParticipant*>& ps) {
  std::vector<int32_t> out;
  for (const auto* p : ps)
    for (int64_t i = 0; i < p->similarity_done(); ++i) {
      const int32_t* q = p->similarity.data() + 3 * i;
      const int neg = p->similarity_answer[i];
      if (neg < 0 || neg > 2) continue;
      out.push_back(q[(neg + 1) % 3]);
      out.push_back(q[(neg + 2) % 3]);
      out.push_back(q[neg]);
    }
  return out;
}

namespace {

// A scenario sentence for a reward over the features ("more table, less laptop").
std::string scenario_text(const Dataset& d, const std::vector<float>& w,
                          std::vector<std::string>* involved) {
  std::string s = "You want the robot to have";
  bool first = true;
  for (int k = 0; k < d.feature_count(); ++k) {
    if (std::abs(w[k]) < 1e-6f) continue;
    involved->push_back(d.feature_names[k]);
    s += std::string(first ? " " : " and ") + (w[k] > 0 ? "more " : "less ") + d.feature_names[k];
    first = false;
  }
  return s + ".";
}

}  // namespace

std::string simulated_participant_id(int u) {
  char id[32];
  std::snprintf(id, sizeof id, "sim%02d", u + 1);
  return id;
}

Study simulate_cohort(const CohortConfig& c) {
  Study s = new_study(c.env, c.trajectories, c.seed);
  const Dataset d = study_dataset(s);
  Teacher t;
  t.beta = c.beta;
  t.mistake = c.mistake;
  validate(t, d.feature_count());
  Rng rng(seed_from_key("study_simulate", c.seed));
  for (int u = 0; u < c.users; ++u) {
    StudyParticipant p =
        plan_participant(d, simulated_participant_id(u), c.similarity, c.preference, c.seed);
    p.reward.assign(d.feature_count(), 0.f);
    const bool both = u % 5 < 3;
    const int only = int(rng.uniform_int(uint64_t(d.feature_count())));
    double norm = 0;
    for (int k = 0; k < d.feature_count(); ++k) {
      if (!both && k != only) continue;
      p.reward[k] = float((rng.uniform() < 0.5 ? -1 : 1) * rng.uniform(0.3, 1.0));
      norm += double(p.reward[k]) * p.reward[k];
    }
    for (float& w : p.reward) w = float(w / std::sqrt(norm));
    p.scenario = scenario_text(d, p.reward, &p.scenario_features);
    simulate_answers(d, p, t, rng);
    s.participants.push_back(std::move(p));
  }
  return s;
}

}  // namespace sirl
