#include "jobs/task_runner.h"

#include <chrono>
#include <stdexcept>

#include "datasets/grid_robot.h"
#include "datasets/jaco_robot.h"
#include "engine/fpe.h"
#include "engine/methods.h"
#include "engine/tpa.h"
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
    std::shared_ptr<const Dataset> d;
    if (env == "grid")
      d = std::make_shared<const Dataset>(make_grid_dataset());
    else if (env == "jaco")
      d = std::make_shared<const Dataset>(make_jaco_dataset(profile_.jaco));
    else
      throw std::invalid_argument("environment " + env + " is not available");
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

std::shared_ptr<const Representation> RunContext::representation(const std::string& key,
                                                                 const Task& t) {
  {
    std::lock_guard lock(mu_);
    auto it = reps_.find(key);
    if (it != reps_.end()) return it->second;
  }
  // A resumed run: rebuild φ from its committed record.
  const TaskRecord rec = load_(key);
  auto r = std::make_shared<Representation>();
  const Hyper& h = profile_.hyper.at(t.env);
  r->shape = phi_shape(dataset(t.env).input_dim, h);
  r->params = rec.arrays.at("params").data;
  if (r->params.size() != r->shape.param_count())
    throw std::runtime_error(key + ": stored φ has " + std::to_string(r->params.size()) +
                             " parameters, the profile's φ " +
                             std::to_string(r->shape.param_count()));
  r->method = t.variant.method;
  r->vae_pretrain = t.variant.vae;
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
  const TaskRecord rec = load_(key);
  auto v = std::make_shared<VaeModel>();
  const Hyper& h = profile_.hyper.at(env);
  v->shape = make_vae_shape(dataset(env).input_dim, h.phi_hidden, h.embedding_dim);
  v->params = rec.arrays.at("params").data;
  if (v->params.size() != v->shape.param_count())
    throw std::runtime_error(key + ": stored VAE does not match the profile's widths");
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
  if (t.kind == TaskKind::vae) return;
  r.text["method"] = method_name(t.variant.method);
  r.text["variant"] = t.variant.name();
  r.num["vae"] = t.variant.vae;
  r.num["N"] = double(t.N);
  if (t.kind == TaskKind::tpa) {
    r.num["M"] = double(t.M);
    r.num["frozen"] = t.frozen;
  }
}

}  // namespace

TaskRecord run_task(const Task& t, RunContext& ctx) {
  const auto start = std::chrono::steady_clock::now();
  TaskRecord r;
  r.key = t.key;
  r.kind = kind_name(t.kind);
  describe_cell(t, r);
  const Hyper& h = ctx.profile().hyper.at(t.env);
  const Dataset& d = ctx.dataset(t.env);
  try {
    switch (t.kind) {
      case TaskKind::vae: {
        auto v = std::make_shared<VaeModel>(train_vae(d, h, task_seed(t.env, t.seed, "vae")));
        r.arrays["params"] = array(v->params);
        r.arrays["loss_curve"] = array(v->loss_curve);
        r.num["flops"] = v->train_flops;
        ctx.keep(t.key, std::shared_ptr<const VaeModel>(v));
        break;
      }
      case TaskKind::rep: {
        const QueryBundle& b = ctx.bundle(t.env, t.seed);
        std::shared_ptr<const VaeModel> vae;
        if (t.variant.vae || t.variant.method == Method::vae) vae = ctx.vae(t.env, t.seed);
        MethodConfig c{t.variant.method, t.N, t.variant.vae, h, 1};
        auto rep = std::make_shared<Representation>(
            train_representation(d, b, c, task_seed(t.env, t.seed, "phi"), vae.get()));
        r.arrays["params"] = array(rep->params);
        r.arrays["loss_curve"] = array(rep->loss_curve);
        std::string widths;
        for (int w : rep->shape.widths) widths += (widths.empty() ? "" : ",") + std::to_string(w);
        r.text["widths"] = widths;
        r.text["hyper"] = describe(h);
        r.num["flops"] = rep->train_flops;
        ctx.keep(t.key, std::shared_ptr<const Representation>(rep));
        break;
      }
      case TaskKind::fpe: {
        const QueryBundle& b = ctx.bundle(t.env, t.seed);
        const std::string rk = rep_key(t.env, t.seed, t.variant, t.N);
        const FpeResult f = evaluate_fpe(*ctx.representation(rk, t), d, b.fpe);
        r.num["fpe"] = f.fpe;
        r.num["train_mse"] = f.train_mse;
        r.num["flops"] = 0;
        break;
      }
      case TaskKind::tpa: {
        const QueryBundle& b = ctx.bundle(t.env, t.seed);
        const std::string rk = rep_key(t.env, t.seed, t.variant, t.N);
        const TpaResult res =
            evaluate_tpa(*ctx.representation(rk, t), d, b.tpa, TpaConfig{t.M, t.frozen, h, 1},
                         task_seed(t.env, t.seed, "tpa"));
        r.num["tpa"] = res.mean;
        r.num["tpa_std"] = res.stddev;
        r.num["flops"] = res.train_flops;
        std::vector<float> acc(res.accuracy.begin(), res.accuracy.end());
        const uint64_t R = acc.size();
        r.arrays["accuracy"] = array(std::move(acc));
        r.arrays["loss_curves"] = array(res.loss_curves, {R, uint64_t(res.epochs)});
        r.arrays["phi_drift"] = array(res.phi_drift);
        break;
      }
    }
  } catch (const std::exception& e) {
    throw std::runtime_error("task " + t.key + ": " + e.what());
  }
  r.num["seconds"] =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

}  // namespace sirl
