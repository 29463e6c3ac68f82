#include "jobs/study_tasks.h"

#include <cmath>
#include <map>
#include <stdexcept>

#include "datasets/environments.h"
#include "engine/tpa.h"
#include "jobs/task_outputs.h"

namespace sirl {

namespace {

std::string study_rep_key(int64_t k, Method m) {
  return "study/s" + std::to_string(k) + "/" + method_name(m) + "/rep";
}
std::string heldout_key(const std::string& id) {
  return "study/heldout/" + id + "/rep";
}
std::string tpa_key(const std::string& id) {
  return "study/tpa/" + id;
}
const char* kSimulatedKey = "study/simulated";

Task study_task(std::string key, TaskKind kind, const CohortConfig& c) {
  Task t;
  t.key = std::move(key);
  t.kind = kind;
  t.env = c.env;
  return t;
}

// The rough sizes the cost model needs: φ's shape on the study's Ξ and the TPA networks.
struct StudySizes {
  MlpShape phi, head_frozen, head_unfrozen;
  int64_t trajectories, triplets, train_pairs;
};
StudySizes study_sizes(const Profile& p, const StudyAnalysisConfig& c) {
  const CohortConfig& co = p.study.cohort;
  const EnvSpec& e = env_spec(co.env);
  EnvConfig ec;
  ec.jaco.trajectories = co.trajectories;
  StudySizes s;
  s.phi = phi_shape(e.input_dim(ec), c.hyper);
  s.head_frozen = tpa_network(s.phi, c.hyper, true);
  s.head_unfrozen = tpa_network(s.phi, c.hyper, false);
  s.trajectories = e.trajectories(ec);
  s.triplets = int64_t(co.users) * co.similarity;
  s.train_pairs = std::llround(c.train_fraction * double(co.preference));
  return s;
}

// One frozen-or-unfrozen TPA cell over `heads` heads of M pairs.
double tpa_flops(const MlpShape& net, int64_t heads, int64_t M, int epochs) {
  return double(heads) * train_flops(net, 2 * M, epochs);
}

}  // namespace

StudyAnalysisConfig study_config(const Profile& p) {
  const StudyPlan& sp = p.study;
  StudyAnalysisConfig c;
  c.hyper = paper_hyper(sp.cohort.env);
  c.hyper.sirl.epochs = sp.epochs;
  c.hyper.tpa.epochs = sp.tpa_epochs;
  c.seeds = sp.seeds;
  c.cv_splits = sp.splits;
  c.threads = 1;
  c.random_frozen = sp.random_frozen;
  return c;
}

void add_study_tasks(Plan& plan, const Profile& p) {
  if (!p.study.enabled) return;
  const CohortConfig& co = p.study.cohort;
  const StudyAnalysisConfig c = study_config(p);
  const StudySizes z = study_sizes(p, c);
  const double embed =
      z.phi.forward_flops(int(std::min<int64_t>(c.fpe_trajectories, z.trajectories)));
  int sirl0 = -1, random0 = -1;
  for (int64_t k = 0; k < c.seeds; ++k)
    for (Method m : {Method::sirl, Method::random}) {
      Task t = study_task(study_rep_key(k, m), TaskKind::study_rep, co);
      t.seed = k;
      t.variant = Variant{m, false};
      t.flops =
          (m == Method::sirl ? train_flops(z.phi, 3 * z.triplets, c.hyper.sirl.epochs) : 0) + embed;
      const int i = add_task(plan, std::move(t));
      if (k == 0) (m == Method::sirl ? sirl0 : random0) = i;
    }
  // The other mode's Random is evaluated beside the chosen one: three cells per participant.
  const double cells =
      tpa_flops(z.head_frozen, c.cv_splits, z.train_pairs, c.hyper.tpa.epochs) * 2 +
      tpa_flops(z.head_unfrozen, c.cv_splits, z.train_pairs, c.hyper.tpa.epochs);
  for (int u = 0; u < co.users; ++u) {
    const std::string id = simulated_participant_id(u);
    Task h = study_task(heldout_key(id), TaskKind::study_heldout, co);
    h.participant = id;
    h.flops = train_flops(z.phi, 3 * (z.triplets - co.similarity), c.hyper.sirl.epochs);
    const int held = add_task(plan, std::move(h));
    Task t = study_task(tpa_key(id), TaskKind::study_tpa, co);
    t.participant = id;
    t.deps = {sirl0, random0, held};
    t.flops = cells + tpa_flops(z.head_frozen, c.cv_splits, z.train_pairs, c.hyper.tpa.epochs);
    add_task(plan, std::move(t));
  }
  Task s = study_task(kSimulatedKey, TaskKind::study_simulated, co);
  s.deps = {sirl0, random0};
  const int64_t M = std::llround(c.train_fraction * double(c.simulated_queries));
  s.flops = tpa_flops(z.head_frozen, c.simulated_rewards, M, c.hyper.tpa.epochs) * 2 +
            tpa_flops(z.head_unfrozen, c.simulated_rewards, M, c.hyper.tpa.epochs);
  add_task(plan, std::move(s));
}

void run_study_rep_task(const Task& t, RunContext& ctx, TaskRecord& r) {
  const StudyAnalysisConfig c = study_config(ctx.profile());
  const Dataset& d = ctx.study_dataset();
  const std::vector<int32_t> pooled = study_triplets(ctx.study());
  const Representation phi = t.variant.method == Method::sirl
                                 ? study_sirl(d, pooled, c, int(t.seed))
                                 : study_random(d, c, int(t.seed));
  put_representation(phi, r);
  r.num["triplets"] = double(pooled.size() / 3);
  r.num["fpe"] = study_fpe(phi, d, c);
  r.num["flops"] = phi.train_flops;
  ctx.keep(t.key, std::make_shared<const Representation>(get_representation(r)));
}

void run_study_heldout_task(const Task& t, RunContext& ctx, TaskRecord& r) {
  const Representation phi =
      study_heldout(ctx.study(), ctx.study_dataset(), t.participant, study_config(ctx.profile()));
  if (phi.params.empty())
    throw std::runtime_error("no other participant answered a similarity query");
  put_representation(phi, r);
  r.text["participant"] = t.participant;
  r.num["flops"] = phi.train_flops;
  ctx.keep(t.key, std::make_shared<const Representation>(get_representation(r)));
}

void run_study_tpa_task(const Task& t, RunContext& ctx, TaskRecord& r) {
  const Study& s = ctx.study();
  const StudyParticipant* p = s.find(t.participant);
  if (!p) throw std::runtime_error("no participant '" + t.participant + "' in the cohort");
  const ParticipantTpa a = study_participant_tpa(
      *p, ctx.study_dataset(), *ctx.representation(study_rep_key(0, Method::sirl)),
      *ctx.representation(study_rep_key(0, Method::random)),
      *ctx.representation(heldout_key(t.participant)), study_config(ctx.profile()));
  r.text["participant"] = t.participant;
  r.num["ok"] = a.ok;
  r.num["both_features"] = a.both_features;
  r.num["real_sirl"] = a.real_sirl;
  r.num["real_random"] = a.real_random;
  r.num["real_random_other"] = a.real_random_other;
  r.num["heldout_sirl"] = a.heldout_sirl;
  r.num["flops"] = t.flops;  // estimated: TPA cells do not count their own FLOPs here
}

void run_study_simulated_task(const Task& t, RunContext& ctx, TaskRecord& r) {
  const SimulatedTpa a = study_simulated_tpa(
      ctx.study_dataset(), *ctx.representation(study_rep_key(0, Method::sirl)),
      *ctx.representation(study_rep_key(0, Method::random)), study_config(ctx.profile()));
  // Numbers, not float arrays: the accuracies stay exact doubles, as analyze_study returns them.
  auto put = [&](const std::string& name, const std::vector<double>& v) {
    r.num[name + "_count"] = double(v.size());
    for (size_t i = 0; i < v.size(); ++i) r.num[name + "_" + std::to_string(i)] = v[i];
  };
  put("sirl", a.sirl);
  put("random", a.random);
  put("random_other", a.random_other);
  r.num["flops"] = t.flops;
}

StudyAnalysis assemble_study(const Profile& p, const std::vector<TaskRecord>& records) {
  std::map<std::string, const TaskRecord*> by_key;
  for (const auto& r : records) by_key[r.key] = &r;
  auto need = [&](const std::string& key) -> const TaskRecord& {
    auto it = by_key.find(key);
    if (it == by_key.end()) throw std::runtime_error("the study's task " + key + " has not run");
    return *it->second;
  };
  const StudyAnalysisConfig c = study_config(p);
  StudyAnalysis a;
  a.triplets = int64_t(need(study_rep_key(0, Method::sirl)).num.at("triplets"));
  for (int64_t k = 0; k < c.seeds; ++k) {
    a.fpe_sirl.push_back(need(study_rep_key(k, Method::sirl)).num.at("fpe"));
    a.fpe_random.push_back(need(study_rep_key(k, Method::random)).num.at("fpe"));
  }
  for (int u = 0; u < p.study.cohort.users; ++u) {
    const std::string id = simulated_participant_id(u);
    const TaskRecord& r = need(tpa_key(id));
    ParticipantTpa t;
    t.ok = r.num.at("ok") != 0;
    t.both_features = r.num.at("both_features") != 0;
    t.real_sirl = r.num.at("real_sirl");
    t.real_random = r.num.at("real_random");
    t.real_random_other = r.num.at("real_random_other");
    t.heldout_sirl = r.num.at("heldout_sirl");
    add_participant(a, id, t);
  }
  const TaskRecord& s = need(kSimulatedKey);
  auto vec = [&](const std::string& name) {
    std::vector<double> v(size_t(s.num.at(name + "_count")));
    for (size_t i = 0; i < v.size(); ++i) v[i] = s.num.at(name + "_" + std::to_string(i));
    return v;
  };
  set_simulated(a, SimulatedTpa{vec("sirl"), vec("random"), vec("random_other")});
  return a;
}

}  // namespace sirl
