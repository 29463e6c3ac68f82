#include "experiment/study_tasks.h"

#include <cmath>
#include <map>
#include <stdexcept>

#include "datasets/environments.h"
#include "datasets/queries.h"
#include "engine/tpa.h"
#include "experiment/simulation_tasks.h"
#include "experiment/task_config.h"
#include "experiment/task_outputs.h"
#include "experiment/task_settings.h"

namespace sirl {

using C = H5Table::Column;

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
const char* kAnalysisKey = "study/analysis";

// A study task of `kind` on the cohort's environment, fields set (add_task keys it).
Task study_task(TaskKind kind, const Profile& p) {
  Task t;
  t.kind = kind;
  t.env = p.study.cohort.env;
  return t;
}
Task study_rep_task(const Profile& p, int64_t k, Method m) {
  Task t = study_task(study_rep_kind(), p);
  t.seed = k;
  t.variant = Variant{m, false};
  return t;
}
Task study_heldout_task(const Profile& p, const std::string& id) {
  Task t = study_task(study_heldout_kind(), p);
  t.participant = id;
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
  if (e.set_sample) e.set_sample(ec, co.trajectories, 0);
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
  return double(heads) * net.train_flops(2 * M, epochs);
}

}  // namespace

StudyAnalysisConfig study_config(const Profile& p) {
  const StudyPlan& sp = p.study;
  StudyAnalysisConfig c;
  c.hyper = paper_hyper(sp.cohort.env);
  c.hyper.sirl.epochs = sp.epochs;
  c.hyper.tpa.epochs = sp.tpa_epochs;
  c.hyper.precision = p.precision;
  c.seeds = sp.seeds;
  c.cv_splits = sp.splits;
  c.threads = 1;
  c.random_frozen = sp.random_frozen;
  return c;
}

void add_study_tasks(Plan& plan, const Profile& p) {
  if (!p.study.enabled) return;
  for (int64_t k = 0; k < p.study.seeds; ++k)
    for (Method m : {Method::sirl, Method::random}) add_task(plan, p, study_rep_task(p, k, m));
  for (int u = 0; u < p.study.cohort.users; ++u) {
    const std::string id = simulated_participant_id(u);
    add_task(plan, p, study_heldout_task(p, id));
    Task t = study_task(study_tpa_kind(), p);
    t.participant = id;
    add_task(plan, p, std::move(t));
  }
  add_task(plan, p, study_task(study_simulated_kind(), p));
  add_task(plan, p, study_task(study_analysis_kind(), p));
}

namespace {

// The pooled SIRL and Random of training seed 0: what every TPA evaluation of the study reads.
std::vector<Task> seed0_representations(const Profile& p) {
  return {study_rep_task(p, 0, Method::sirl), study_rep_task(p, 0, Method::random)};
}

void study_rep_cost(Task& t, const Profile& p) {
  const StudyAnalysisConfig c = study_config(p);
  const StudySizes z = study_sizes(p, c);
  const double embed =
      z.phi.forward_flops(int(std::min<int64_t>(c.fpe_trajectories, z.trajectories)));
  t.flops =
      (t.variant.method == Method::sirl ? z.phi.train_flops(3 * z.triplets, c.hyper.sirl.epochs)
                                        : 0) +
      embed;
}

void study_heldout_cost(Task& t, const Profile& p) {
  const StudyAnalysisConfig c = study_config(p);
  const StudySizes z = study_sizes(p, c);
  t.flops = z.phi.train_flops(3 * (z.triplets - p.study.cohort.similarity), c.hyper.sirl.epochs);
}

// Three cells per participant (the other mode's Random is evaluated beside the chosen one), and
// the Held-out φ's frozen cell.
void study_tpa_cost(Task& t, const Profile& p) {
  const StudyAnalysisConfig c = study_config(p);
  const StudySizes z = study_sizes(p, c);
  const double frozen = tpa_flops(z.head_frozen, c.cv_splits, z.train_pairs, c.hyper.tpa.epochs);
  const double cells =
      frozen * 2 + tpa_flops(z.head_unfrozen, c.cv_splits, z.train_pairs, c.hyper.tpa.epochs);
  t.flops = cells + frozen;
}

void study_simulated_cost(Task& t, const Profile& p) {
  const StudyAnalysisConfig c = study_config(p);
  const StudySizes z = study_sizes(p, c);
  const int64_t M = std::llround(c.train_fraction * double(c.simulated_queries));
  t.flops = tpa_flops(z.head_frozen, c.simulated_rewards, M, c.hyper.tpa.epochs) * 2 +
            tpa_flops(z.head_unfrozen, c.simulated_rewards, M, c.hyper.tpa.epochs);
}

// The study's configuration, compiled with the task, on the cores the scheduler gave it (results
// do not depend on the thread count).
StudyAnalysisConfig config_for(const Task& t) {
  StudyAnalysisConfig c = *t.compiled().study;
  c.threads = t.threads;
  return c;
}

void run_study_rep(const Task& t, RunContext& ctx, TaskRecord& r) {
  const StudyAnalysisConfig c = config_for(t);
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

void run_study_heldout(const Task& t, RunContext& ctx, TaskRecord& r) {
  const Representation phi =
      study_heldout(ctx.study(), ctx.study_dataset(), t.participant, config_for(t));
  if (phi.params.empty())
    throw std::runtime_error("no other participant answered a similarity query");
  put_representation(phi, r);
  r.num["flops"] = phi.train_flops;
  ctx.keep(t.key, std::make_shared<const Representation>(get_representation(r)));
}

void run_study_tpa(const Task& t, RunContext& ctx, TaskRecord& r) {
  const Study& s = ctx.study();
  const StudyParticipant* p = s.find(t.participant);
  if (!p) throw std::runtime_error("no participant '" + t.participant + "' in the cohort");
  const ParticipantTpa a = study_participant_tpa(
      *p, ctx.study_dataset(), *ctx.representation(study_rep_key(0, Method::sirl)),
      *ctx.representation(study_rep_key(0, Method::random)),
      *ctx.representation(heldout_key(t.participant)), config_for(t));
  r.num["ok"] = a.ok;
  r.num["both_features"] = a.both_features;
  r.num["real_sirl"] = a.real_sirl;
  r.num["real_random"] = a.real_random;
  r.num["real_random_other"] = a.real_random_other;
  r.num["heldout_sirl"] = a.heldout_sirl;
  r.num["flops"] = t.flops;  // estimated: TPA cells do not count their own FLOPs here
}

void run_study_simulated(const Task& t, RunContext& ctx, TaskRecord& r) {
  const SimulatedTpa a =
      study_simulated_tpa(ctx.study_dataset(), *ctx.representation(study_rep_key(0, Method::sirl)),
                          *ctx.representation(study_rep_key(0, Method::random)), config_for(t));
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

// Every study task whose record the analysis reads: each training seed's SIRL and Random, each
// participant's TPA, the simulated preferences' TPA.
std::vector<Task> analysis_inputs(const Task&, const Profile& p) {
  std::vector<Task> in;
  for (int64_t k = 0; k < p.study.seeds; ++k)
    for (Method m : {Method::sirl, Method::random}) in.push_back(study_rep_task(p, k, m));
  for (int u = 0; u < p.study.cohort.users; ++u) {
    Task t = study_task(study_tpa_kind(), p);
    t.participant = simulated_participant_id(u);
    in.push_back(std::move(t));
  }
  in.push_back(study_task(study_simulated_kind(), p));
  return in;
}

// The analysis as the rows of /tables/study (a long table, one value per row): "fpe" per training
// seed, "real" and "heldout" per participant, "simulated" per reward; SIRL, Random in the mode
// the study evaluates it in, and Random in the other mode ("random_other").
void put_analysis_rows(const StudyAnalysis& a, TaskRecord& r) {
  int64_t n = 0;
  auto row = [&](const char* measure, const char* method, const std::string& unit, bool both,
                 double value) {
    const std::string i = "/" + std::to_string(n++);
    r.text["measure" + i] = measure;
    r.text["method" + i] = method;
    r.text["unit" + i] = unit;
    r.num["both_features" + i] = both;
    r.num["value" + i] = value;
  };
  for (size_t k = 0; k < a.fpe_sirl.size(); ++k) {
    row("fpe", "sirl", std::to_string(k), false, a.fpe_sirl[k]);
    row("fpe", "random", std::to_string(k), false, a.fpe_random[k]);
  }
  for (size_t j = 0; j < a.participants.size(); ++j) {
    const std::string& id = a.participants[j];
    const bool both = a.both_features[j] != 0;
    row("real", "sirl", id, both, a.real_sirl[j]);
    row("real", "random", id, both, a.real_random[j]);
    row("real", "random_other", id, both, a.real_random_other[j]);
    row("heldout", "sirl", id, both, a.heldout_sirl[j]);
    row("heldout", "random", id, both, a.heldout_random[j]);
    row("heldout", "random_other", id, both, a.heldout_random_other[j]);
  }
  for (size_t i = 0; i < a.simulated_sirl.size(); ++i) {
    row("simulated", "sirl", std::to_string(i), false, a.simulated_sirl[i]);
    row("simulated", "random", std::to_string(i), false, a.simulated_random[i]);
    row("simulated", "random_other", std::to_string(i), false, a.simulated_random_other[i]);
  }
  r.num["rows"] = double(n);
}

void run_study_analysis(const Task& t, RunContext& ctx, TaskRecord& r) {
  const StudyAnalysisConfig& c = *t.compiled().study;
  std::vector<TaskRecord> in;
  for (const std::string& key : t.input_keys_in_order) in.push_back(ctx.record(key));
  const StudyAnalysis a = assemble_study(c, t.compiled().study_users, in);
  put_analysis_rows(a, r);
  r.num["triplets"] = double(a.triplets);
  r.text["random_mode"] = c.random_frozen ? "frozen" : "unfrozen";
  r.num["seeds"] = c.seeds;
  r.num["cv_splits"] = c.cv_splits;
  r.num["sirl_epochs"] = c.hyper.sirl.epochs;
  r.num["tpa_epochs"] = c.hyper.tpa.epochs;
  r.num["flops"] = 0;  // it trains nothing
}

void study_analysis_cost(Task& t, const Profile&) {
  t.flops = 0;
}

// Every study task runs with the study; none keeps weights in the results file (the networks are
// regenerable, and 3.1 M floats each on JacoRobot).
std::string the_study(const Task&) {
  return "study";
}
const RateClass& sirl_rate(const Task&) {
  return sirl_training_rate();
}
// A study TPA task mixes frozen and unfrozen cells; the slower rate bounds its time.
const RateClass& unfrozen_tpa_rate(const Task&) {
  return tpa_training_rate(false);
}
void describe_participant(const Task& t, TaskRecord& r) {
  describe_env_and_seed(t, r);
  r.text["participant"] = t.participant;
}

// The study's tasks multiply in the run's top-level precision.
bool top_precision_is_bf16(const Task&, const Profile& p) {
  return p.precision == "bf16";
}

// Every study task reads [study] and the run's top-level precision.
std::string study_settings(const Task&, const Profile& p) {
  return describe_study(p.study) + "precision = " + p.precision + "\n";
}

// What every study task's runner reads: the analysis' configuration and the cohort's size (both
// from [study] and the top-level precision, which study_settings describes).
void compile_study(const Task&, const Profile& p, TaskConfig& c) {
  c.study = study_config(p);
  c.study_users = p.study.cohort.users;
}

}  // namespace

const TaskKindSpec& study_rep_kind() {
  static const TaskKindSpec kind{
      .name = "study_rep",
      .description =
          "user study: SIRL on the pooled answers or Random, per training seed, with its FPE",
      .key = [](const Task& t) { return study_rep_key(t.seed, t.variant.method); },
      .inputs = [](const Task&, const Profile&) { return std::vector<Task>{}; },
      .settings = study_settings,
      .cost = study_rep_cost,
      .rate = sirl_rate,
      .shard_group = the_study,
      .bf16_products = top_precision_is_bf16,
      .stores_weights = false,
      .describe = describe_env_and_seed,
      .run = run_study_rep,
      .table = {},
      .compile = compile_study,
  };
  return kind;
}

const TaskKindSpec& study_heldout_kind() {
  static const TaskKindSpec kind{
      .name = "study_heldout",
      .description = "user study: SIRL without one participant's answers",
      .key = [](const Task& t) { return heldout_key(t.participant); },
      .inputs = [](const Task&, const Profile&) { return std::vector<Task>{}; },
      .settings = study_settings,
      .cost = study_heldout_cost,
      .rate = sirl_rate,
      .shard_group = the_study,
      .bf16_products = top_precision_is_bf16,
      .stores_weights = false,
      .describe = describe_participant,
      .run = run_study_heldout,
      .table = {},
      .compile = compile_study,
  };
  return kind;
}

const TaskKindSpec& study_tpa_kind() {
  static const TaskKindSpec kind{
      .name = "study_tpa",
      .description = "user study: one participant's Real and Held-out TPA (cross-validated)",
      .key = [](const Task& t) { return tpa_key(t.participant); },
      .inputs =
          [](const Task& t, const Profile& p) {
            std::vector<Task> in = seed0_representations(p);
            in.push_back(study_heldout_task(p, t.participant));
            return in;
          },
      .settings = study_settings,
      .cost = study_tpa_cost,
      .rate = unfrozen_tpa_rate,
      .shard_group = the_study,
      .bf16_products = top_precision_is_bf16,
      .stores_weights = false,
      .describe = describe_participant,
      .run = run_study_tpa,
      .table = {},
      .compile = compile_study,
  };
  return kind;
}

const TaskKindSpec& study_simulated_kind() {
  static const TaskKindSpec kind{
      .name = "study_simulated",
      .description = "user study: TPA on simulated perfect preferences",
      .key = [](const Task&) { return std::string(kSimulatedKey); },
      .inputs = [](const Task&, const Profile& p) { return seed0_representations(p); },
      // Its simulated preferences are TPA sets (datasets/queries.h): their held-out rule too.
      .settings = [](const Task& t,
                     const Profile& p) { return study_settings(t, p) + kTpaHeldOutRule; },
      .cost = study_simulated_cost,
      .rate = unfrozen_tpa_rate,
      .shard_group = the_study,
      .bf16_products = top_precision_is_bf16,
      .stores_weights = false,
      .describe = describe_env_and_seed,
      .run = run_study_simulated,
      .table = {},
      .compile = compile_study,
  };
  return kind;
}

const TaskKindSpec& study_analysis_kind() {
  static const TaskKindSpec kind{
      .name = "study_analysis",
      .description = "user study: the analysis from the study's tasks, as /tables/study",
      .key = [](const Task&) { return std::string(kAnalysisKey); },
      .inputs = analysis_inputs,
      .settings = study_settings,
      .cost = study_analysis_cost,
      .rate = sirl_rate,  // no FLOPs: what a call costs
      .shard_group = the_study,
      .bf16_products = top_precision_is_bf16,
      .stores_weights = false,
      .describe = describe_env_and_seed,
      .run = run_study_analysis,
      .table = {"study",
                "study_analysis",
                {{"env", C::String, "env"},
                 {"measure", C::String, "measure"},
                 {"method", C::String, "method"},
                 {"unit", C::String, "unit"},
                 {"both_features", C::Int, "both_features"},
                 {"value", C::Double, "value"},
                 {"random_mode", C::String, "random_mode"},
                 {"triplets", C::Int, "triplets"},
                 {"seeds", C::Int, "seeds"},
                 {"cv_splits", C::Int, "cv_splits"},
                 {"sirl_epochs", C::Int, "sirl_epochs"},
                 {"tpa_epochs", C::Int, "tpa_epochs"}},
                "rows"},
      .compile = compile_study,
  };
  return kind;
}

namespace {
[[maybe_unused]] const TaskKindRegistration registered_study_kinds[]{
    TaskKindRegistration(study_rep_kind()), TaskKindRegistration(study_heldout_kind()),
    TaskKindRegistration(study_tpa_kind()), TaskKindRegistration(study_simulated_kind()),
    TaskKindRegistration(study_analysis_kind())};
}  // namespace

StudyAnalysis assemble_study(const Profile& p, const std::vector<TaskRecord>& records) {
  return assemble_study(study_config(p), p.study.cohort.users, records);
}

StudyAnalysis assemble_study(const StudyAnalysisConfig& c, int users,
                             const std::vector<TaskRecord>& records) {
  std::map<std::string, const TaskRecord*> by_key;
  for (const auto& r : records) by_key[r.key] = &r;
  auto need = [&](const std::string& key) -> const TaskRecord& {
    auto it = by_key.find(key);
    if (it == by_key.end()) throw std::runtime_error("the study's task " + key + " has not run");
    return *it->second;
  };
  StudyAnalysis a;
  a.triplets = int64_t(need(study_rep_key(0, Method::sirl)).num.at("triplets"));
  for (int64_t k = 0; k < c.seeds; ++k) {
    a.fpe_sirl.push_back(need(study_rep_key(k, Method::sirl)).num.at("fpe"));
    a.fpe_random.push_back(need(study_rep_key(k, Method::random)).num.at("fpe"));
  }
  for (int u = 0; u < users; ++u) {
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
