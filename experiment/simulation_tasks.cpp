#include "experiment/simulation_tasks.h"

#include <algorithm>
#include <initializer_list>
#include <sstream>
#include <string>
#include <string_view>

#include "datasets/environments.h"
#include "datasets/exact_text.h"
#include "datasets/queries.h"
#include "engine/convergence.h"
#include "engine/fpe.h"
#include "engine/linear_tpa.h"
#include "engine/methods.h"
#include "engine/tpa.h"
#include "experiment/calibration.h"
#include "experiment/cost_model.h"
#include "experiment/simulation_costs.h"
#include "experiment/task_config.h"
#include "experiment/task_outputs.h"
#include "experiment/task_settings.h"
#include "kernels/vae.h"
#include "results/external_embeddings.h"

namespace sirl {

std::string vae_key(const std::string& env, int64_t seed) {
  return env + "/s" + std::to_string(seed) + "/vae";
}

namespace {
// "<env>/s<seed>[/<teacher>]/<variant>[/N<N>]/"
std::string cell_prefix(const std::string& env, int64_t seed, const std::string& teacher,
                        const Variant& v, int64_t N) {
  std::string k = env + "/s" + std::to_string(seed) + "/";
  if (!teacher.empty()) k += teacher + "/";
  k += v.name();
  if (uses_queries(v.method)) k += "/N" + std::to_string(N);
  return k + "/";
}
std::string cell_prefix(const Task& t) {
  return cell_prefix(t.env, t.seed, t.teacher, t.variant, t.N);
}
// The teacher of the φ a cell reads: none for a method that learns from no answers.
std::string rep_teacher(const Variant& v, const std::string& teacher) {
  return uses_queries(v.method) ? teacher : "";
}
}  // namespace

std::string rep_key(const std::string& env, int64_t seed, const Variant& v, int64_t N,
                    const std::string& teacher) {
  return cell_prefix(env, seed, rep_teacher(v, teacher), v, N) + "rep";
}

Task experiment_cell(TaskKind kind, const std::string& env, int64_t seed, const Variant& v,
                     int64_t N, const std::string& teacher) {
  Task t;
  t.kind = kind;
  t.env = env;
  t.seed = seed;
  t.variant = v;
  t.N = uses_queries(v.method) ? N : 0;
  const bool heads_learn = kind == tpa_kind() || kind == robust_tpa_kind();
  t.teacher = heads_learn ? teacher : rep_teacher(v, teacher);
  return t;
}

namespace {

// ---- what the runners share ----

// The convergence verdict of a loss curve (engine/convergence.h), as record fields.
void record_convergence(const std::vector<float>& curve, TaskRecord& r) {
  const Convergence c = check_convergence(curve);
  r.num["converged"] = c.converged;
  r.num["loss_relative_change"] = c.relative_change;
}

// φ over the whole trajectory space: the embedding [T, d] (a product of the run, not only an
// input of FPE/TPA) and the dead-unit fraction of each hidden layer. Returns its FLOPs.
double record_embedding(const Representation& rep, const Dataset& d, TaskRecord& r) {
  const EmbeddingPass e = embed_all(rep, d.inputs.data(), d.count);
  r.arrays["embedding"] =
      TaskRecord::Array::of(e.embedding, {uint64_t(d.count), uint64_t(rep.dim())});
  r.arrays["dead_fraction"] = TaskRecord::Array::of(e.dead_fraction);
  return rep.shape.forward_flops(int(d.count));
}

Task vae_input(const Task& t) {
  Task v;
  v.kind = vae_kind();
  v.env = t.env;
  v.seed = t.seed;
  v.hyper = t.hyper;
  return v;
}
std::string active_key(const std::string& env, int64_t seed, Selection rule,
                       const std::string& teacher) {
  return env + "/s" + std::to_string(seed) + "/" + (teacher.empty() ? "" : teacher + "/") +
         "active/" + selection_name(rule);
}
Task active_input(const Task& t) {
  Task a;
  a.kind = active_kind();
  a.env = t.env;
  a.seed = t.seed;
  a.teacher = t.teacher;
  a.hyper = t.hyper;
  a.variant = Variant{Method::sirl, false, t.variant.selection};
  return a;
}
bool reads_active(const Variant& v) {
  return v.selection != Selection::uniform;
}

Task rep_input(const Task& t) {
  Task r = experiment_cell(rep_kind(), t.env, t.seed, t.variant, t.N, t.teacher);
  r.hyper = t.hyper;
  return r;
}
// What a cell of φ reads: its rep task, or nothing for a reference (φ is a function of Ξ).
std::vector<Task> cell_inputs(const Task& t, const Profile&) {
  if (is_reference(t.variant.method)) return {};
  return {rep_input(t)};
}
// The φ a cell scores.
std::shared_ptr<const Representation> cell_representation(const Task& t, RunContext& ctx) {
  if (is_reference(t.variant.method))
    return std::make_shared<const Representation>(
        reference_representation(t.variant.method, ctx.dataset(t.env)));
  return ctx.representation(t.input(rep_kind()));
}
std::string input_rep_key(const Task& t) {
  return rep_key(t.env, t.seed, t.variant, t.N, t.teacher);
}

// Every task of the experiment shards with its φ; a VAE or an active query set goes to every
// shard that needs it.
std::string by_representation(const Task& t) {
  return t.kind == vae_kind() || t.kind == active_kind() ? "" : input_rep_key(t);
}

// What a record says about its task: env and seed, and for φ and its cells the method and sizes.
void describe_variant(const Task& t, TaskRecord& r) {
  describe_env_and_seed(t, r);
  r.text["method"] = method_name(t.variant.method);
  r.text["variant"] = t.variant.name();
  r.text["selection"] = selection_name(t.variant.selection);
  r.text["teacher"] = t.teacher;  // "" = the profile's main teacher
  r.num["vae"] = t.variant.vae;
  r.num["N"] = double(t.N);
  if (is_reference(t.variant.method)) r.num["reference"] = 1;  // a ceiling or floor, not a method
}
// A robustness cell also names its teacher, the noise axis and level, and how far the answers
// it learned from are from the perfect oracle's (AnswerError).
void record_teacher(const Task& t, RunContext& ctx, TaskRecord& r) {
  r.text["teacher"] = t.teacher;
  if (const auto& tp = t.compiled().teacher) {
    r.text["axis"] = tp->axis;
    r.num["level"] = tp->level;
  }
  const AnswerError& e = ctx.bundle(t.env, t.seed, t.teacher).answer_error;
  r.num["similarity_error"] = e.similarity;
  r.num["preference_error"] = e.preference;
}
void describe_tpa(const Task& t, TaskRecord& r) {
  describe_variant(t, r);
  r.num["M"] = double(t.M);
  r.num["frozen"] = t.frozen;
  r.num["best_mode"] = is_best_mode(t.variant, t.frozen);
  r.num["in_main"] = t.in_main;  // a cell of Fig. 5 ([tpa]), of Fig. 7 ([ablation]), or both
  r.num["in_ablation"] = t.in_ablation;
}

// ---- vae ----

bool name_vae_cell(TaskRecord& r);

void run_vae(const Task& t, RunContext& ctx, TaskRecord& r) {
  const auto checkpoint = ctx.checkpointer(t.key);
  const VaeModel v = train_vae(ctx.dataset(t.env), t.hyper_values(),
                               task_seed(t.env, t.seed, "vae"), {t.threads, checkpoint.get()});
  put_vae(v, r);
  r.num["flops"] = v.train_flops;
  record_convergence(v.loss_curve, r);
  name_vae_cell(r);
  ctx.keep(t.key, std::make_shared<const VaeModel>(get_vae(r)));
}

// The tables' cell fields of a VAE record: the VAE baseline's encoder is what it trains, so its
// method and variant are "vae". (Outputs, not described fields: the task's digest does not read
// them, and records of engines before 0.13.0, which lack them, are completed with them.)
bool vae_lacks_cell_fields(const TaskRecord& r) {
  return !r.text.count("variant");
}
bool name_vae_cell(TaskRecord& r) {
  r.text["method"] = "vae";
  r.text["variant"] = "vae";
  return true;
}

// ---- rep ----

bool reads_vae(const Variant& v) {
  return v.vae || v.method == Method::vae;
}

// The hyper-parameters a representation's training reads: φ's shape and the precision, its
// method's schedule, and the VAE's when it starts from (or is) the VAE's encoder.
std::string rep_hyper(const Variant& v, const Hyper& h) {
  std::string s = hyper_lines(h, {"phi.", "precision"});
  if (const char* own = method_spec(v.method).training.hyper_prefix; *own) {
    std::string lines = hyper_lines(h, {own});
    // Under the paper's "fixed" schedule a preference φ's bits do not depend on the stop rule's
    // minimum and tolerance: its digest leaves the rule out, as before the rule existed, so
    // results computed then are still found.
    if (h.pref_stop == "fixed") {
      std::string kept, line;
      std::istringstream in(lines);
      while (std::getline(in, line))
        if (!line.starts_with("pref.stop")) kept += line + "\n";
      lines = kept;
    }
    s += lines;
  }
  if (reads_vae(v)) s += hyper_lines(h, {"vae."});
  return s;
}

// An external method's "training" is reading its embedding of Ξ for this (env, seed, N): the
// record holds it as a learned φ's holds its own, so FPE and TPA read it the same way.
void run_external_rep(const Task& t, RunContext& ctx, TaskRecord& r) {
  const ExternalMethod& m = *t.compiled().external;
  const Dataset& d = ctx.dataset(t.env);
  ExternalEmbedding e = read_external_embedding(m.embeddings, m.xxh3, t.env, t.seed, t.N, d.count);
  const Representation rep = table_representation(std::move(e.values), d.count, e.dim, d.input_dim);
  put_representation(rep, r);
  r.arrays["embedding"] = TaskRecord::Array::of(rep.table, {uint64_t(d.count), uint64_t(e.dim)});
  r.text["embeddings_file"] = m.embeddings;
  r.text["embeddings_xxh3"] = m.xxh3;
  r.num["flops"] = 0;
  r.num["protocol_flops"] = 0;
  if (!t.teacher.empty()) r.text["teacher"] = t.teacher;
  ctx.keep(t.key, std::make_shared<const Representation>(get_representation(r)));
}

void run_rep(const Task& t, RunContext& ctx, TaskRecord& r) {
  if (t.variant.method == Method::external) return run_external_rep(t, ctx, r);
  const Hyper& h = t.hyper_values();
  const Dataset& d = ctx.dataset(t.env);
  std::shared_ptr<const VaeModel> vae;
  if (reads_vae(t.variant)) vae = ctx.vae(t.input(vae_kind()));
  const auto checkpoint = ctx.checkpointer(t.key);
  const MethodConfig c{t.variant.method, t.N, t.variant.vae, h};
  const QueryBundle* bundle = &ctx.bundle(t.env, t.seed, t.teacher);
  QueryBundle chosen;  // an active variant: the same bundle with the triplets it chose
  if (reads_active(t.variant)) {
    chosen = *bundle;
    chosen.similarity = *ctx.triplets(t.input(active_kind()));
    bundle = &chosen;
  }
  // SIRL's φ starts from the same initialisation whichever way its triplets were chosen.
  const Representation rep = train_representation(d, *bundle, c, task_seed(t.env, t.seed, "phi"),
                                                  vae.get(), {t.threads, checkpoint.get()});
  put_representation(rep, r);
  r.text["hyper"] = rep_hyper(t.variant, h);  // what this φ was trained with
  // FLOPs spent in this task: the VAE method's φ is the VAE task's encoder, trained there.
  r.num["flops"] =
      (t.variant.method == Method::vae ? 0.0 : rep.train_flops) + record_embedding(rep, d, r);
  // The protocol's count: what the epochs skipped at a fixed point would have added.
  r.num["protocol_flops"] = r.num["flops"] + rep.skipped_flops;
  if (!t.teacher.empty()) r.text["teacher"] = t.teacher;
  if (method_spec(t.variant.method).training.train) record_convergence(rep.loss_curve, r);
  ctx.keep(t.key, std::make_shared<const Representation>(get_representation(r)));
}

// ---- fpe ----

// FPE's labelled trajectories are the true features whoever the teacher (its split is drawn
// from a stream no teacher touches, so every teacher's φ is probed on the same rows).
void run_fpe(const Task& t, RunContext& ctx, TaskRecord& r) {
  const auto rep = cell_representation(t, ctx);
  const FpeSplit& split = ctx.bundle(t.env, t.seed).fpe;
  const FpeResult f = evaluate_fpe(*rep, ctx.dataset(t.env), split);
  r.num["fpe"] = f.fpe;
  r.num["train_mse"] = f.train_mse;
  if (t.variant.method == Method::raw) r.num["ridge_weight"] = f.ridge_weight;
  r.num["flops"] = probe_flops(int64_t(split.train.size() + split.test.size()), rep->dim());
}
// The same, and what a robustness row says of its teacher's answers.
void run_robust_fpe(const Task& t, RunContext& ctx, TaskRecord& r) {
  run_fpe(t, ctx, r);
  record_teacher(t, ctx, r);
}

// ---- tpa ----

// Converged when every head's loss curve is (the fraction tells how many were); the relative
// change reported is the median head's.
void record_heads_convergence(const TpaResult& res, TaskRecord& r) {
  const uint64_t R = res.accuracy.size();
  int converged = 0;
  std::vector<double> change;
  for (uint64_t k = 0; k < R; ++k) {
    const auto* c = res.loss_curves.data() + k * res.epochs;  // NaN after a head's stop
    const Convergence v = check_convergence(std::vector<float>(c, c + res.head_epochs[k]));
    converged += v.converged;
    change.push_back(v.relative_change);
  }
  std::sort(change.begin(), change.end());
  r.num["converged"] = converged == int(R);
  r.num["converged_fraction"] = R ? double(converged) / double(R) : 0.0;
  r.num["loss_relative_change"] = R ? change[R / 2] : 0.0;
}

void run_tpa(const Task& t, RunContext& ctx, TaskRecord& r) {
  const auto checkpoint = ctx.checkpointer(t.key);
  const Hyper& h = t.hyper_values();
  const TpaResult res = evaluate_tpa(
      *cell_representation(t, ctx), ctx.dataset(t.env), ctx.bundle(t.env, t.seed, t.teacher).tpa,
      TpaConfig{t.M, t.frozen, h}, task_seed(t.env, t.seed, "tpa"), {t.threads, checkpoint.get()});
  r.num["tpa"] = res.mean;
  r.num["tpa_std"] = res.stddev;
  r.num["flops"] = res.train_flops;
  r.num["protocol_flops"] = res.protocol_flops;
  const uint64_t R = res.accuracy.size();
  r.arrays["accuracy"] =
      TaskRecord::Array::of(std::vector<float>(res.accuracy.begin(), res.accuracy.end()));
  r.arrays["train_accuracy"] = TaskRecord::Array::of(
      std::vector<float>(res.train_accuracy.begin(), res.train_accuracy.end()));
  double train_mean = 0;
  for (double a : res.train_accuracy) train_mean += a / double(R);
  r.num["tpa_train"] = train_mean;
  r.arrays["loss_curves"] = TaskRecord::Array::of(res.loss_curves, {R, uint64_t(res.epochs)});
  r.arrays["phi_drift"] = TaskRecord::Array::of(res.phi_drift);
  // Each head's epochs trained; a head below the cap stopped by tpa.stop = "converged".
  r.arrays["head_epochs"] =
      TaskRecord::Array::of(std::vector<float>(res.head_epochs.begin(), res.head_epochs.end()));
  r.text["stop"] = tpa_stop_rule(h, t.frozen).converged ? "converged" : "fixed";  // its heads'
  if (!res.shadow_epochs.empty()) {  // tpa.shadow_rel_tol: the heads a shadow rule would stop
    r.num["tpa_shadow"] = res.shadow_mean;
    r.arrays["shadow_epochs"] = TaskRecord::Array::of(
        std::vector<float>(res.shadow_epochs.begin(), res.shadow_epochs.end()));
    r.arrays["shadow_accuracy"] = TaskRecord::Array::of(
        std::vector<float>(res.shadow_accuracy.begin(), res.shadow_accuracy.end()));
  }
  record_heads_convergence(res, r);
  if (!t.teacher.empty()) r.text["teacher"] = t.teacher;
}
void run_robust_tpa(const Task& t, RunContext& ctx, TaskRecord& r) {
  run_tpa(t, ctx, r);
  record_teacher(t, ctx, r);
}

// ---- linear evaluation ----

// The penalty grid, folds, Newton stopping rule and rank cut are the protocol's
// (docs/linear-evaluation.md); no hyper-parameter of the profile enters a linear head.
LinearBtOptions linear_options() {
  return {};
}

void describe_linear_tpa(const Task& t, TaskRecord& r) {
  describe_tpa(t, r);
  r.text["protocol"] = "linear";
  r.num["best_mode"] = 1;  // φ is frozen under linear evaluation: every method's only mode
}

std::string linear_tpa_settings(const Task& t, const Profile& p) {
  const LinearBtOptions o = linear_options();
  std::string grid;
  for (double a : o.alpha_grid) grid += " " + exact_number(a);
  return describe_data(p, t.env) + describe_queries(queries_for(p, t.teacher)) + kTpaHeldOutRule +
         "linear standardised ridge-cv folds " + std::to_string(o.folds) + " alpha_grid" + grid +
         " single_pair_alpha " + exact_number(o.single_pair_alpha) + " tolerance " +
         exact_number(o.tolerance) + " floor " + exact_number(o.floor) + " max_iterations " +
         std::to_string(o.max_iterations) + " rank_tolerance " + exact_number(o.rank_tolerance) +
         "\n";
}

void run_linear_tpa(const Task& t, RunContext& ctx, TaskRecord& r) {
  const LinearTpaResult res = evaluate_linear_tpa(*cell_representation(t, ctx), ctx.dataset(t.env),
                                                  ctx.bundle(t.env, t.seed, t.teacher).tpa, t.M,
                                                  linear_options(), t.threads);
  r.num["tpa"] = res.mean;
  r.num["tpa_std"] = res.stddev;
  r.num["flops"] = res.flops;
  r.num["protocol_flops"] = res.flops;
  const auto floats = [](const auto& v) { return std::vector<float>(v.begin(), v.end()); };
  r.arrays["accuracy"] = TaskRecord::Array::of(floats(res.accuracy));
  r.arrays["train_accuracy"] = TaskRecord::Array::of(floats(res.train_accuracy));
  r.arrays["newton_iterations"] = TaskRecord::Array::of(floats(res.iterations));
  r.arrays["span_rank"] = TaskRecord::Array::of(floats(res.rank));
  r.arrays["ridge_alpha"] = TaskRecord::Array::of(floats(res.alpha));
  double own_pairs = 0;  // accuracy on the heads' own training pairs
  for (double a : res.train_accuracy) own_pairs += a / double(res.train_accuracy.size());
  r.num["tpa_train"] = own_pairs;
  r.num["newton_iterations"] = *std::max_element(res.iterations.begin(), res.iterations.end());
  // Not "converged": that names a training's loss curve (/tables/training).
  r.num["newton_converged"] = res.converged;
  if (!t.teacher.empty()) r.text["teacher"] = t.teacher;
}

// ---- active ----

void run_active(const Task& t, RunContext& ctx, TaskRecord& r) {
  const ActiveConfig& c = *t.compiled().active;
  const auto checkpoint = ctx.checkpointer(t.key);
  // The teacher as the bundle has it (an attend teacher's mask drawn for this seed).
  const Teacher& teacher = ctx.bundle(t.env, t.seed, t.teacher).config.teacher;
  const ActiveQueries a =
      select_active_queries(ctx.dataset(t.env), teacher, c, task_seed(t.env, t.seed, "active"),
                            {t.threads, checkpoint.get()});
  put_triplets(a.queries, r);
  r.arrays["batch_score"] = TaskRecord::Array::of(a.batch_score);
  r.arrays["pool_score"] = TaskRecord::Array::of(a.pool_score);
  r.num["rounds"] = a.rounds;
  r.num["flops"] = a.train_flops;
  ctx.keep(t.key, std::make_shared<const TripletSet>(get_triplets(r)));
}

void describe_active(const Task& t, TaskRecord& r) {
  describe_env_and_seed(t, r);
  r.text["selection"] = selection_name(t.variant.selection);
  r.text["teacher"] = t.teacher;
}

std::string tpa_cell_key(const Task& t) {
  return cell_prefix(t) + "tpa/M" + std::to_string(t.M) + (t.frozen ? "/frozen" : "/unfrozen");
}

// ---- compiled once per task when it is planned (experiment/task_config.h) ----

// A representation: its point's hyper-parameters with its method's stop rule ([pref] stop); an
// external method's declaration.
void compile_rep(const Task& t, const Profile& p, TaskConfig& c) {
  c.hyper = rep_task_hyper(p, t.env, t.hyper, t.variant);
  if (t.variant.method == Method::external) c.external = external_method(p, t.variant.external);
}
// A TPA cell: its point's hyper-parameters, with its method's stop rule ([tpa] stop).
void compile_tpa(const Task& t, const Profile& p, TaskConfig& c) {
  c.hyper = tpa_cell_hyper(p, t.env, t.hyper, t.variant);
}
// An active task: its rounds, rule and budget at its point's hyper-parameters.
void compile_active(const Task& t, const Profile& p, TaskConfig& c) {
  compile_env_point(t, p, c);
  c.active = active_config(t, p, *c.hyper);
}

// ---- settings: what each kind reads of the profile (experiment/task_settings.h) ----

std::string vae_settings(const Task& t, const Profile& p) {
  return describe_data(p, t.env) + hyper_lines(t.hyper_values(), {"phi.", "vae.", "precision"});
}

std::string rep_settings(const Task& t, const Profile& p) {
  if (t.variant.method == Method::external)
    return describe_data(p, t.env) + describe_external(*t.compiled().external);
  // Every φ is handed its seed's query bundle (methods that ask nothing ignore it).
  return describe_data(p, t.env) + describe_queries(queries_for(p, t.teacher)) +
         rep_hyper(t.variant, t.hyper_values());
}

// The probe's split comes from the main teacher's bundle; a robustness row also states its own
// teacher's answer error.
std::string fpe_settings(const Task& t, const Profile& p) {
  return describe_data(p, t.env) + describe_queries(p.queries) +
         (t.teacher.empty() ? "" : describe_queries(queries_for(p, t.teacher))) +
         (t.variant.method == Method::raw ? "probe ridge leave-one-out 1e-8..1e2\n" : "");
}

std::string tpa_settings(const Task& t, const Profile& p) {
  return describe_data(p, t.env) + describe_queries(queries_for(p, t.teacher)) + kTpaHeldOutRule +
         hyper_lines(t.hyper_values(), {"phi.", "tpa.", "precision"});
}

std::string active_settings(const Task& t, const Profile& p) {
  return describe_data(p, t.env) + describe_queries(queries_for(p, t.teacher)) +
         describe_active(p.active.at(t.env)) +
         hyper_lines(t.hyper_values(), {"phi.", "sirl.", "precision"});
}

using C = H5Table::Column;

// The columns a robustness row adds: who taught, on which axis at which level, and how far its
// answers were from the perfect oracle's.
const std::vector<TableColumn> kTeacherColumns{{"teacher", C::String, "teacher"},
                                               {"axis", C::String, "axis"},
                                               {"level", C::Double, "level"},
                                               {"similarity_error", C::Double, "similarity_error"},
                                               {"preference_error", C::Double, "preference_error"}};

void drop_columns(CellTableSpec& t, std::initializer_list<std::string_view> names) {
  std::erase_if(t.columns, [&](const TableColumn& c) {
    return std::find(names.begin(), names.end(), std::string_view(c.name)) != names.end();
  });
}

}  // namespace

bool lacks_cell_fields(const TaskRecord& r) {
  return r.kind != "vae" && r.text.count("variant") && !r.text.count("selection");
}

bool complete_cell_fields(TaskRecord& r) {
  if (!lacks_cell_fields(r)) return false;
  const Variant variant = parse_variant(r.text.at("variant"));
  r.text["selection"] = selection_name(variant.selection);
  r.text.emplace("teacher", "");  // a robustness record names its own
  if (r.num.count("frozen") && !r.num.count("best_mode"))
    r.num["best_mode"] = is_best_mode(variant, r.num.at("frozen") != 0);
  return true;
}

// The rate classes of the simulation's kinds (experiment/calibration.h): each one the kind's own
// training on the calibration sample.
const RateClass& sirl_training_rate() {
  static const RateClass rate{
      "rep_sirl", [](const CalibrationSample& s, int scale) {
        return train_representation(
                   *s.data, s.bundle,
                   MethodConfig{Method::sirl, 200, false, calibration_lengths(s, scale)}, 1)
            .train_flops;
      }};
  return rate;
}

namespace {
const RateClass& preference_training_rate() {
  static const RateClass rate{
      "rep_pref", [](const CalibrationSample& s, int scale) {
        return train_representation(
                   *s.data, s.bundle,
                   MethodConfig{Method::multipref10, 200, false, calibration_lengths(s, scale)}, 1)
            .train_flops;
      }};
  return rate;
}
// The class a representation's training is timed by: its method's (MethodTraining::rate_class).
// An untrained φ (VAE, Random) costs only its embedding of Ξ, timed as the preference class.
const RateClass& rep_training_rate(const Variant& v) {
  const std::string_view want = method_spec(v.method).training.rate_class;
  if (want.empty() || want == preference_training_rate().name) return preference_training_rate();
  if (want == sirl_training_rate().name) return sirl_training_rate();
  throw std::logic_error("method " + std::string(method_name(v.method)) +
                         " names an unknown rate class '" + std::string(want) + "'");
}
const RateClass& vae_training_rate() {
  static const RateClass rate{
      "vae", [](const CalibrationSample& s, int scale) {
        return train_vae(*s.data, calibration_lengths(s, scale), 1).train_flops;
      }};
  return rate;
}
// FPE is φ over the probe's rows, once: no epochs.
const RateClass& fpe_probe_rate() {
  static const RateClass rate{
      "fpe",
      [](const CalibrationSample& s, int) {
        evaluate_fpe(s.phi, *s.data, s.bundle.fpe);
        return s.phi.shape.forward_flops(int(s.bundle.fpe.train.size() + s.bundle.fpe.test.size()));
      },
      true};
  return rate;
}
// The heads of a cell at M = 100 pairs (or as many as the sample's splits hold).
double calibrate_heads(const CalibrationSample& s, int scale, bool frozen) {
  const int64_t M = std::min<int64_t>(100, s.bundle.tpa[0].train);
  return evaluate_tpa(s.phi, *s.data, s.bundle.tpa,
                      TpaConfig{M, frozen, calibration_lengths(s, scale)}, 1)
      .train_flops;
}
}  // namespace

const RateClass& tpa_training_rate(bool frozen) {
  static const RateClass frozen_heads{
      "tpa_frozen", [](const CalibrationSample& s, int k) { return calibrate_heads(s, k, true); }};
  static const RateClass unfrozen_heads{"tpa_unfrozen", [](const CalibrationSample& s, int k) {
                                          return calibrate_heads(s, k, false);
                                        }};
  return frozen ? frozen_heads : unfrozen_heads;
}

const TaskKindSpec& vae_kind() {
  static const TaskKindSpec kind{
      .name = "vae",
      .description = "a VAE over Ξ per (env, seed): pre-training and the VAE baseline",
      .key = [](const Task& t) { return vae_key(t.env, t.seed); },
      .inputs = [](const Task&, const Profile&) { return std::vector<Task>{}; },
      .settings = vae_settings,
      .cost = vae_cost,
      .rate = [](const Task&) -> const RateClass& { return vae_training_rate(); },
      .shard_group = by_representation,
      .bf16_products = env_precision_is_bf16,
      .stores_weights = true,
      .describe = describe_env_and_seed,
      .run = run_vae,
      .table = {},
      .lacks_fields = vae_lacks_cell_fields,
      .complete_fields = name_vae_cell,
      .compile = compile_env_point,
  };
  return kind;
}

const TaskKindSpec& rep_kind() {
  static const TaskKindSpec kind{
      .name = "rep",
      .description = "a representation φ per (env, seed, method, N), its embedding of Ξ",
      .key = [](const Task& t) { return input_rep_key(t); },
      .inputs =
          [](const Task& t, const Profile&) {
            std::vector<Task> in;
            if (reads_vae(t.variant)) in.push_back(vae_input(t));
            if (reads_active(t.variant)) in.push_back(active_input(t));
            return in;
          },
      .settings = rep_settings,
      .cost = rep_cost,
      .rate = [](const Task& t) -> const RateClass& { return rep_training_rate(t.variant); },
      .shard_group = by_representation,
      .bf16_products = env_precision_is_bf16,
      .stores_weights = true,
      .describe = describe_variant,
      .run = run_rep,
      .table = {},
      .lacks_fields = lacks_cell_fields,
      .complete_fields = complete_cell_fields,
      .compile = compile_rep,
  };
  return kind;
}

const TaskKindSpec& fpe_kind() {
  static const TaskKindSpec kind{
      .name = "fpe",
      .description = "FPE of one φ: a linear probe's held-out error",
      .key = [](const Task& t) { return cell_prefix(t) + "fpe"; },
      .inputs = cell_inputs,
      .settings = fpe_settings,
      .cost = fpe_cost,
      .rate = [](const Task&) -> const RateClass& { return fpe_probe_rate(); },
      .shard_group = by_representation,
      .bf16_products = never_bf16,
      .stores_weights = true,
      .describe = describe_variant,
      .run = run_fpe,
      .table = {"fpe",
                "fpe",
                {{"env", C::String, "env"},
                 {"method", C::String, "method"},
                 {"variant", C::String, "variant"},
                 {"vae", C::Int, "vae"},
                 {"N", C::Int, "N"},
                 {"seed", C::Int, "seed"},
                 {"fpe", C::Double, "fpe"},
                 {"train_mse", C::Double, "train_mse"},
                 {"selection", C::String, "selection"},
                 {"teacher", C::String, "teacher"},
                 {"hyper_point", C::String, "hyper_point", true},
                 {"reference", C::Int, "reference", true}}},
      .lacks_fields = lacks_cell_fields,
      .complete_fields = complete_cell_fields,
      .compile = compile_env_point,
  };
  return kind;
}

const TaskKindSpec& tpa_kind() {
  static const TaskKindSpec kind{
      .name = "tpa",
      .description = "TPA of one φ at M pairs, frozen or unfrozen: 20 reward heads",
      .key = tpa_cell_key,
      .inputs = cell_inputs,
      .settings = tpa_settings,
      .cost = tpa_cost,
      .rate = [](const Task& t) -> const RateClass& { return tpa_training_rate(t.frozen); },
      .shard_group = by_representation,
      .bf16_products = env_precision_is_bf16,
      .stores_weights = true,
      .describe = describe_tpa,
      .run = run_tpa,
      .table = {"tpa",
                "tpa",
                {{"env", C::String, "env"},
                 {"method", C::String, "method"},
                 {"variant", C::String, "variant"},
                 {"vae", C::Int, "vae"},
                 {"frozen", C::Int, "frozen"},
                 {"N", C::Int, "N"},
                 {"M", C::Int, "M"},
                 {"seed", C::Int, "seed"},
                 {"tpa", C::Double, "tpa"},
                 {"tpa_std", C::Double, "tpa_std"},
                 {"tpa_train", C::Double, "tpa_train"},
                 {"in_main", C::Int, "in_main"},
                 {"in_ablation", C::Int, "in_ablation"},
                 {"selection", C::String, "selection"},
                 {"teacher", C::String, "teacher"},
                 {"best_mode", C::Int, "best_mode"},
                 {"hyper_point", C::String, "hyper_point", true},
                 // the paper's reward head, or linear evaluation (records of tpa_linear)
                 {"protocol", C::String, "protocol", true, "paper"},
                 {"reference", C::Int, "reference", true}},
                nullptr,
                {"tpa_linear"}},
      .lacks_fields = lacks_cell_fields,
      .complete_fields = complete_cell_fields,
      .compile = compile_tpa,
  };
  return kind;
}

// Linear evaluation's cells: rows of /tables/tpa (protocol "linear"), so no table of their own.
const TaskKindSpec& linear_tpa_kind() {
  static const TaskKindSpec kind{
      .name = "tpa_linear",
      .description = "TPA of one φ at M pairs under linear evaluation: 20 linear heads, Newton",
      .key =
          [](const Task& t) { return cell_prefix(t) + "tpa/M" + std::to_string(t.M) + "/linear"; },
      .inputs = cell_inputs,
      .settings = linear_tpa_settings,
      .cost = linear_tpa_cost,
      // Dense linear algebra in double on a stored embedding, as the FPE probe's.
      .rate = [](const Task&) -> const RateClass& { return fpe_probe_rate(); },
      .shard_group = by_representation,
      .bf16_products = never_bf16,
      .stores_weights = true,
      .describe = describe_linear_tpa,
      .run = run_linear_tpa,
      .table = {},
      .compile = compile_env_point,
  };
  return kind;
}

// The robustness cells: FPE and TPA cells of a noisy teacher, in tables of their own so the
// main grid's tables (and their digests) do not change when a profile adds noise axes. A twin is
// its main kind with its own name, runner and table: the main table's columns but `dropped`, and
// kTeacherColumns (the teacher among them) after the method's.
namespace {
TaskKindSpec robustness_twin(const TaskKindSpec& main, const char* name, const char* description,
                             void (*run)(const Task&, RunContext&, TaskRecord&),
                             std::initializer_list<std::string_view> dropped) {
  TaskKindSpec k = main;
  k.name = name;
  k.description = description;
  k.run = run;
  k.table.kind = name;
  k.table.name = name;
  k.table.more_kinds.clear();  // a noisy teacher's cells are the paper's protocol only
  drop_columns(k.table, dropped);
  k.table.columns.insert(k.table.columns.begin() + 4, kTeacherColumns.begin(),
                         kTeacherColumns.end());
  return k;
}
}  // namespace

const TaskKindSpec& robust_fpe_kind() {
  static const TaskKindSpec kind = robustness_twin(
      fpe_kind(), "robust_fpe", "FPE of one φ trained on a noisy teacher's answers ([robustness])",
      run_robust_fpe, {"teacher"});
  return kind;
}

const TaskKindSpec& robust_tpa_kind() {
  // No in_main, in_ablation: its cells belong to no figure's grid.
  static const TaskKindSpec kind =
      robustness_twin(tpa_kind(), "robust_tpa",
                      "TPA of one φ, heads trained on a noisy teacher's labels ([robustness])",
                      run_robust_tpa, {"in_main", "in_ablation", "teacher"});
  return kind;
}

const TaskKindSpec& active_kind() {
  static const TaskKindSpec kind{
      .name = "active",
      .description = "the triplets an active SIRL variant asks, chosen round by round",
      .key =
          [](const Task& t) { return active_key(t.env, t.seed, t.variant.selection, t.teacher); },
      .inputs = [](const Task&, const Profile&) { return std::vector<Task>{}; },
      .settings = active_settings,
      .cost = active_cost,
      .rate = [](const Task&) -> const RateClass& { return sirl_training_rate(); },
      .shard_group = by_representation,
      .bf16_products = env_precision_is_bf16,
      .stores_weights = true,
      .describe = describe_active,
      .run = run_active,
      .table = {},
      .compile = compile_active,
  };
  return kind;
}

namespace {
[[maybe_unused]] const TaskKindRegistration registered_simulation_kinds[]{
    TaskKindRegistration(vae_kind()),        TaskKindRegistration(rep_kind()),
    TaskKindRegistration(fpe_kind()),        TaskKindRegistration(tpa_kind()),
    TaskKindRegistration(linear_tpa_kind()), TaskKindRegistration(robust_fpe_kind()),
    TaskKindRegistration(robust_tpa_kind()), TaskKindRegistration(active_kind())};
}  // namespace

}  // namespace sirl
