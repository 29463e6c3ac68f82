#include "jobs/task_runner.h"

#include <algorithm>
#include <chrono>
#include <stdexcept>

#include "datasets/environments.h"
#include "engine/convergence.h"
#include "engine/fpe.h"
#include "engine/methods.h"
#include "engine/tpa.h"
#include "jobs/task_kinds.h"
#include "jobs/task_outputs.h"
#include "kernels/rng.h"

namespace sirl {

uint64_t task_seed(const std::string& env, int64_t seed, const char* stream) {
  return seed_from_key(env + "/s" + std::to_string(seed) + "/" + stream);
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

const QueryBundle& RunContext::bundle(const std::string& env, int64_t seed) {
  const std::string key = env + "/s" + std::to_string(seed);
  const Dataset& d = dataset(env);
  std::call_once(once("bundle/" + key), [&] {
    auto b = std::make_shared<const QueryBundle>(
        make_query_bundle(d, profile_.queries, task_seed(env, seed, "queries")));
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
void RunContext::release(const std::string& key) {
  std::lock_guard lock(mu_);
  reps_.erase(key);
  vaes_.erase(key);
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

std::shared_ptr<const VaeModel> RunContext::vae(const std::string& env, int64_t seed) {
  const std::string key = vae_key(env, seed);
  {
    std::lock_guard lock(mu_);
    auto it = vaes_.find(key);
    if (it != vaes_.end()) return it->second;
  }
  auto v = std::make_shared<const VaeModel>(get_vae(load_(key)));
  keep(key, v);
  return v;
}

namespace {

TaskRecord::Array array(std::vector<float> data, std::vector<uint64_t> dims = {}) {
  if (dims.empty()) dims = {uint64_t(data.size())};
  return TaskRecord::Array{std::move(dims), std::move(data)};
}

void describe_cell(const Task& t, TaskRecord& r) {
  r.text["env"] = t.env;
  r.num["seed"] = double(t.seed);
  if (t.kind != TaskKind::rep && t.kind != TaskKind::fpe && t.kind != TaskKind::tpa) return;
  r.text["method"] = method_name(t.variant.method);
  r.text["variant"] = t.variant.name();
  r.num["vae"] = t.variant.vae;
  r.num["N"] = double(t.N);
  if (t.kind == TaskKind::tpa) {
    r.num["M"] = double(t.M);
    r.num["frozen"] = t.frozen;
    r.num["in_main"] = t.in_main;  // a cell of Fig. 5 ([tpa]), of Fig. 7 ([ablation]), or both
    r.num["in_ablation"] = t.in_ablation;
  }
}

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
  r.arrays["embedding"] = array(e.embedding, {uint64_t(d.count), uint64_t(rep.dim())});
  r.arrays["dead_fraction"] = array(e.dead_fraction);
  return rep.shape.forward_flops(int(d.count));
}

}  // namespace

// Each task kind's computation: inputs from the context, outputs into the record (through
// task_outputs' put_*, so a resumed run reads back exactly what a fresh one wrote).
void run_vae_task(const Task& t, RunContext& ctx, TaskRecord& r) {
  const VaeModel v =
      train_vae(ctx.dataset(t.env), ctx.profile().hyper.at(t.env), task_seed(t.env, t.seed, "vae"));
  put_vae(v, r);
  r.num["flops"] = v.train_flops;
  record_convergence(v.loss_curve, r);
  ctx.keep(t.key, std::make_shared<const VaeModel>(get_vae(r)));
}

void run_rep_task(const Task& t, RunContext& ctx, TaskRecord& r) {
  const Hyper& h = ctx.profile().hyper.at(t.env);
  const Dataset& d = ctx.dataset(t.env);
  std::shared_ptr<const VaeModel> vae;
  if (t.variant.vae || t.variant.method == Method::vae) vae = ctx.vae(t.env, t.seed);
  MethodConfig c{t.variant.method, t.N, t.variant.vae, h, 1};
  const Representation rep = train_representation(d, ctx.bundle(t.env, t.seed), c,
                                                  task_seed(t.env, t.seed, "phi"), vae.get());
  put_representation(rep, r);
  r.text["hyper"] = describe(h);
  // FLOPs spent in this task: the VAE method's φ is the VAE task's encoder, trained there.
  r.num["flops"] =
      (t.variant.method == Method::vae ? 0.0 : rep.train_flops) + record_embedding(rep, d, r);
  if (t.variant.method != Method::vae && t.variant.method != Method::random)
    record_convergence(rep.loss_curve, r);
  ctx.keep(t.key, std::make_shared<const Representation>(get_representation(r)));
}

void run_fpe_task(const Task& t, RunContext& ctx, TaskRecord& r) {
  const std::string rk = rep_key(t.env, t.seed, t.variant, t.N);
  const FpeResult f =
      evaluate_fpe(*ctx.representation(rk), ctx.dataset(t.env), ctx.bundle(t.env, t.seed).fpe);
  r.num["fpe"] = f.fpe;
  r.num["train_mse"] = f.train_mse;
  r.num["flops"] = 0;
}

void run_tpa_task(const Task& t, RunContext& ctx, TaskRecord& r) {
  const std::string rk = rep_key(t.env, t.seed, t.variant, t.N);
  const TpaResult res = evaluate_tpa(
      *ctx.representation(rk), ctx.dataset(t.env), ctx.bundle(t.env, t.seed).tpa,
      TpaConfig{t.M, t.frozen, ctx.profile().hyper.at(t.env), 1}, task_seed(t.env, t.seed, "tpa"));
  r.num["tpa"] = res.mean;
  r.num["tpa_std"] = res.stddev;
  r.num["flops"] = res.train_flops;
  const uint64_t R = res.accuracy.size();
  r.arrays["accuracy"] = array(std::vector<float>(res.accuracy.begin(), res.accuracy.end()));
  r.arrays["train_accuracy"] =
      array(std::vector<float>(res.train_accuracy.begin(), res.train_accuracy.end()));
  double train_mean = 0;
  for (double a : res.train_accuracy) train_mean += a / double(R);
  r.num["tpa_train"] = train_mean;
  r.arrays["loss_curves"] = array(res.loss_curves, {R, uint64_t(res.epochs)});
  r.arrays["phi_drift"] = array(res.phi_drift);
  // Converged when every head's loss curve is (the fraction tells how many were).
  int converged = 0;
  std::vector<double> change;
  for (uint64_t k = 0; k < R; ++k) {
    const auto* c = res.loss_curves.data() + k * res.epochs;
    const Convergence v = check_convergence(std::vector<float>(c, c + res.epochs));
    converged += v.converged;
    change.push_back(v.relative_change);
  }
  std::sort(change.begin(), change.end());
  r.num["converged"] = converged == int(R);
  r.num["converged_fraction"] = R ? double(converged) / double(R) : 0.0;
  r.num["loss_relative_change"] = R ? change[R / 2] : 0.0;  // the median head's
}

TaskRecord run_task(const Task& t, RunContext& ctx) {
  const auto start = std::chrono::steady_clock::now();
  TaskRecord r;
  r.key = t.key;
  r.kind = kind_name(t.kind);
  describe_cell(t, r);
  try {
    task_kind(t.kind).run(t, ctx, r);
  } catch (const std::exception& e) {
    throw std::runtime_error("task " + t.key + ": " + e.what());
  }
  r.num["seconds"] =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

}  // namespace sirl
