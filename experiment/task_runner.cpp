#include "experiment/task_runner.h"

#include <chrono>
#include <stdexcept>

#include "datasets/environments.h"
#include "experiment/task_outputs.h"
#include "kernels/gemm_bf16.h"
#include "kernels/rng.h"
#include "probes/cpu_class.h"

namespace sirl {

uint64_t task_seed(const std::string& env, int64_t seed, const char* stream) {
  return seed_from_key(env_spec(env).stream_name() + "/s" + std::to_string(seed) + "/" + stream);
}

RunContext::RunContext(const Profile& p, std::function<TaskRecord(const std::string&)> load)
    : profile_(p), load_(std::move(load)) {}

std::once_flag& RunContext::once(const std::string& key) {
  std::lock_guard lock(mu_);
  auto& f = once_[key];
  if (!f) f = std::make_unique<std::once_flag>();
  return *f;
}

const Dataset& RunContext::dataset(const std::string& env) {
  std::call_once(once("dataset/" + env), [&] {
    auto d = std::make_shared<const Dataset>(env_spec(env).make(profile_.data));
    std::lock_guard lock(mu_);
    datasets_[env] = std::move(d);
  });
  std::lock_guard lock(mu_);
  return *datasets_.at(env);
}

const QueryBundle& RunContext::bundle(const std::string& env, int64_t seed,
                                      const std::string& teacher) {
  const std::string key =
      env + "/s" + std::to_string(seed) + (teacher.empty() ? "" : "/" + teacher);
  const Dataset& d = dataset(env);
  std::call_once(once("bundle/" + key), [&] {
    // Every teacher's bundle draws from the same seed: the same rewards, queries and FPE split;
    // only the answers differ (datasets/query_bundle.h).
    auto b = std::make_shared<const QueryBundle>(
        make_query_bundle(d, queries_for(profile_, teacher), task_seed(env, seed, "queries")));
    std::lock_guard lock(mu_);
    bundles_[key] = std::move(b);
  });
  std::lock_guard lock(mu_);
  return *bundles_.at(key);
}

const Study& RunContext::study() {
  std::call_once(once("study"), [&] {
    auto s = std::make_shared<const Study>(simulate_cohort(profile_.study.cohort));
    std::lock_guard lock(mu_);
    study_ = std::move(s);
  });
  std::lock_guard lock(mu_);
  return *study_;
}

const Dataset& RunContext::study_dataset() {
  const Study& s = study();
  std::call_once(once("study_dataset"), [&] {
    auto d = std::make_shared<const Dataset>(sirl::study_dataset(s));
    std::lock_guard lock(mu_);
    study_dataset_ = std::move(d);
  });
  std::lock_guard lock(mu_);
  return *study_dataset_;
}

void RunContext::keep(const std::string& key, std::shared_ptr<const Representation> r) {
  std::lock_guard lock(mu_);
  reps_[key] = std::move(r);
}
void RunContext::keep(const std::string& key, std::shared_ptr<const VaeModel> v) {
  std::lock_guard lock(mu_);
  vaes_[key] = std::move(v);
}
void RunContext::keep(const std::string& key, std::shared_ptr<const TripletSet> q) {
  std::lock_guard lock(mu_);
  triplets_[key] = std::move(q);
}
void RunContext::release(const std::string& key) {
  std::lock_guard lock(mu_);
  reps_.erase(key);
  vaes_.erase(key);
  triplets_.erase(key);
}

std::shared_ptr<const TripletSet> RunContext::triplets(const std::string& key) {
  {
    std::lock_guard lock(mu_);
    auto it = triplets_.find(key);
    if (it != triplets_.end()) return it->second;
  }
  auto q = std::make_shared<const TripletSet>(get_triplets(load_(key)));
  keep(key, q);
  return q;
}

std::shared_ptr<const Representation> RunContext::representation(const std::string& key) {
  {
    std::lock_guard lock(mu_);
    auto it = reps_.find(key);
    if (it != reps_.end()) return it->second;
  }
  // A resumed run: φ exactly as its record stored it (the fresh path hands out the same).
  auto r = std::make_shared<const Representation>(get_representation(load_(key)));
  keep(key, r);
  return r;
}

std::shared_ptr<const VaeModel> RunContext::vae(const std::string& key) {
  {
    std::lock_guard lock(mu_);
    auto it = vaes_.find(key);
    if (it != vaes_.end()) return it->second;
  }
  auto v = std::make_shared<const VaeModel>(get_vae(load_(key)));
  keep(key, v);
  return v;
}

}  // namespace sirl
