#include "jobs/plan.h"

#include <stdexcept>

#include "datasets/environments.h"
#include "engine/representation.h"
#include "engine/tpa.h"
#include "jobs/study_tasks.h"
#include "jobs/task_kinds.h"
#include "kernels/vae.h"

namespace sirl {

const char* kind_name(TaskKind k) {
  return task_kind(k).name;
}

int Plan::count(TaskKind k) const {
  int n = 0;
  for (const auto& t : tasks) n += t.kind == k;
  return n;
}
double Plan::flops(TaskKind k) const {
  double f = 0;
  for (const auto& t : tasks)
    if (t.kind == k) f += t.flops;
  return f;
}

std::string vae_key(const std::string& env, int64_t seed) {
  return env + "/s" + std::to_string(seed) + "/vae";
}

std::string rep_key(const std::string& env, int64_t seed, const Variant& v, int64_t N) {
  std::string k = env + "/s" + std::to_string(seed) + "/" + v.name();
  if (uses_queries(v.method)) k += "/N" + std::to_string(N);
  return k + "/rep";
}

// Forward+backward ≈ 3× the forward multiply-adds (docs/ARCHITECTURE.md §6).
double train_flops(const MlpShape& s, int64_t rows_per_epoch, int epochs) {
  return 3.0 * s.forward_flops(1) * double(rows_per_epoch) * epochs;
}

int add_task(Plan& plan, Task t) {
  auto it = plan.index.find(t.key);
  if (it != plan.index.end()) return it->second;
  const int i = int(plan.tasks.size());
  plan.index[t.key] = i;
  plan.tasks.push_back(std::move(t));
  return i;
}

namespace {

// Trajectory-space size and input width per environment (what the cost model needs).
struct EnvSize {
  int input_dim;
  int64_t trajectories;
};
EnvSize env_size(const std::string& env, const Profile& p) {
  const EnvSpec& e = env_spec(env);
  return {e.input_dim(p.data), e.trajectories(p.data)};
}

double working_set(const MlpShape& s, int batch_rows) {
  // params, grad, Adam m and v; activations of one batch.
  double act = 0;
  for (int w : s.widths) act += double(w) * batch_rows;
  return 4.0 * (4.0 * double(s.param_count()) + 2 * act);
}

}  // namespace

namespace {

// Adds one environment's tasks for one seed to a plan: a task appears once however many cells
// share it (its key is its identity), and each kind's cost model sits with its constructor.
class SeedPlanner {
 public:
  SeedPlanner(Plan& plan, const Profile& p, const std::string& env, int64_t seed)
      : plan_(plan),
        p_(p),
        env_(env),
        seed_(seed),
        h_(p.hyper.at(env)),
        es_(env_size(env, p)),
        phi_(phi_shape(es_.input_dim, h_)) {}

  int vae() {
    Task t = base(vae_key(env_, seed_), TaskKind::vae);
    const VaeShape vs = make_vae_shape(es_.input_dim, h_.phi_hidden, h_.embedding_dim);
    // training, then one pass over Ξ measuring the posterior (train_vae)
    t.flops = train_flops(vs.encoder, es_.trajectories, h_.vae.epochs) +
              train_flops(vs.decoder, es_.trajectories, h_.vae.epochs) +
              vs.encoder.forward_flops(int(es_.trajectories)) +
              vs.decoder.forward_flops(int(es_.trajectories));
    t.bytes = working_set(vs.encoder, h_.vae.batch) + working_set(vs.decoder, h_.vae.batch);
    return add(std::move(t));
  }

  int rep(const Variant& v, int64_t N) {
    Task t = base(rep_key(env_, seed_, v, N), TaskKind::rep);
    t.variant = v;
    t.N = uses_queries(v.method) ? N : 0;
    if (v.vae || v.method == Method::vae) t.deps.push_back(vae());
    if (v.method == Method::sirl) {
      t.flops = train_flops(phi_, 3 * t.N, h_.sirl.epochs);
      t.bytes = working_set(phi_, 3 * h_.sirl.batch);
    } else if (uses_queries(v.method)) {
      t.flops = train_flops(phi_, 2 * t.N, h_.pref.epochs);
      t.bytes = working_set(phi_, 2 * h_.pref.batch);
    }
    t.flops += phi_.forward_flops(int(es_.trajectories));  // the embedding of Ξ it stores
    return add(std::move(t));
  }

  void fpe(const Variant& v, int64_t N) {
    const int r = rep(v, N);
    Task t = cell_of(r, "fpe", TaskKind::fpe);
    t.flops = phi_.forward_flops(int(p_.queries.fpe_trajectories));
    t.bytes = 4.0 * double(p_.queries.fpe_trajectories) * (es_.input_dim + 16);
    add(std::move(t));
  }

  void tpa(const Variant& v, int64_t N, int64_t M, bool frozen, bool ablation) {
    const int r = rep(v, N);
    Task t =
        cell_of(r, "tpa/M" + std::to_string(M) + (frozen ? "/frozen" : "/unfrozen"), TaskKind::tpa);
    t.M = M;
    t.frozen = frozen;
    const MlpShape net = tpa_network(phi_, h_, frozen);
    t.flops = kTestRewards * train_flops(net, 2 * M, h_.tpa.epochs);
    t.bytes = kTestRewards * working_set(net, 2 * h_.tpa.batch);
    Task& added = plan_.tasks[add(std::move(t))];  // shared by both grids when keys match
    (ablation ? added.in_ablation : added.in_main) = true;
  }

 private:
  Task base(std::string key, TaskKind kind) const {
    Task t;
    t.key = std::move(key);
    t.kind = kind;
    t.env = env_;
    t.seed = seed_;
    return t;
  }
  // A cell evaluating representation task r: its key is r's with "rep" replaced by `suffix`.
  Task cell_of(int r, const std::string& suffix, TaskKind kind) const {
    Task t = plan_.tasks[r];
    t.key = t.key.substr(0, t.key.size() - 3) + suffix;
    t.kind = kind;
    t.deps = {r};
    return t;
  }
  int add(Task t) { return add_task(plan_, std::move(t)); }

  Plan& plan_;
  const Profile& p_;
  const std::string& env_;
  const int64_t seed_;
  const Hyper& h_;
  const EnvSize es_;
  const MlpShape phi_;
};

}  // namespace

Plan make_plan(const Profile& p) {
  Plan plan;
  for (const auto& env : p.envs) {
    const EnvAxes& axes = p.axes.at(env);
    for (int64_t seed : axes.seeds) {
      SeedPlanner s(plan, p, env, seed);
      for (const auto& v : p.fpe_methods)
        for (int64_t N : axes.fpe_N) s.fpe(v, N);
      for (const auto& v : p.tpa.methods)
        for (int64_t N : axes.tpa_N)
          for (int64_t M : axes.tpa_M)
            for (bool fr : frozen_settings(p.tpa, v)) s.tpa(v, N, M, fr, false);
      for (Method m : p.ablation_methods)
        for (bool with_vae : {false, true}) {
          if (with_vae && !accepts_vae_pretrain(m)) continue;
          const Variant v{m, with_vae};
          for (int64_t N : axes.ablation_N)
            for (int64_t M : axes.ablation_M)
              for (bool fr : {true, false}) s.tpa(v, N, M, fr, true);
        }
    }
  }
  add_study_tasks(plan, p);
  return plan;
}

}  // namespace sirl
