#include "jobs/plan.h"

#include <stdexcept>

#include "datasets/environments.h"
#include "engine/representation.h"
#include "engine/tpa.h"
#include "kernels/vae.h"

namespace sirl {

const char* kind_name(TaskKind k) {
  switch (k) {
    case TaskKind::vae:
      return "vae";
    case TaskKind::rep:
      return "rep";
    case TaskKind::fpe:
      return "fpe";
    case TaskKind::tpa:
      return "tpa";
  }
  return "?";
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

// Forward+backward ≈ 3× the forward multiply-adds (docs/ARCHITECTURE.md §6).
double train_flops(const MlpShape& s, int64_t rows_per_epoch, int epochs) {
  return 3.0 * s.forward_flops(1) * double(rows_per_epoch) * epochs;
}

double working_set(const MlpShape& s, int batch_rows) {
  // params, grad, Adam m and v; activations of one batch.
  double act = 0;
  for (int w : s.widths) act += double(w) * batch_rows;
  return 4.0 * (4.0 * double(s.param_count()) + 2 * act);
}

}  // namespace

Plan make_plan(const Profile& p) {
  Plan plan;
  auto add = [&](Task t) -> int {
    auto it = plan.index.find(t.key);
    if (it != plan.index.end()) return it->second;
    const int i = int(plan.tasks.size());
    plan.index[t.key] = i;
    plan.tasks.push_back(std::move(t));
    return i;
  };
  for (const auto& env : p.envs) {
    const Hyper& h = p.hyper.at(env);
    const EnvSize es = env_size(env, p);
    const MlpShape phi = phi_shape(es.input_dim, h);
    const EnvAxes& axes = p.axes.at(env);
    for (int64_t seed : axes.seeds) {
      auto vae = [&]() {
        Task t;
        t.key = vae_key(env, seed);
        t.kind = TaskKind::vae;
        t.env = env;
        t.seed = seed;
        const VaeShape vs = make_vae_shape(es.input_dim, h.phi_hidden, h.embedding_dim);
        // training, then one pass over Ξ measuring the posterior (train_vae)
        t.flops = train_flops(vs.encoder, es.trajectories, h.vae.epochs) +
                  train_flops(vs.decoder, es.trajectories, h.vae.epochs) +
                  vs.encoder.forward_flops(int(es.trajectories)) +
                  vs.decoder.forward_flops(int(es.trajectories));
        t.bytes = working_set(vs.encoder, h.vae.batch) + working_set(vs.decoder, h.vae.batch);
        return add(std::move(t));
      };
      auto rep = [&](const Variant& v, int64_t N) {
        Task t;
        t.kind = TaskKind::rep;
        t.env = env;
        t.seed = seed;
        t.variant = v;
        t.N = uses_queries(v.method) ? N : 0;
        t.key = rep_key(env, seed, v, N);
        if (v.vae || v.method == Method::vae) t.deps.push_back(vae());
        if (v.method == Method::sirl) {
          t.flops = train_flops(phi, 3 * t.N, h.sirl.epochs);
          t.bytes = working_set(phi, 3 * h.sirl.batch);
        } else if (uses_queries(v.method)) {
          t.flops = train_flops(phi, 2 * t.N, h.pref.epochs);
          t.bytes = working_set(phi, 2 * h.pref.batch);
        }
        t.flops += phi.forward_flops(int(es.trajectories));  // the embedding of Ξ it stores
        return add(std::move(t));
      };
      auto fpe = [&](const Variant& v, int64_t N) {
        const int r = rep(v, N);
        Task t = plan.tasks[r];
        t.key = t.key.substr(0, t.key.size() - 3) + "fpe";
        t.kind = TaskKind::fpe;
        t.deps = {r};
        t.flops = phi.forward_flops(int(p.queries.fpe_trajectories));
        t.bytes = 4.0 * double(p.queries.fpe_trajectories) * (es.input_dim + 16);
        add(std::move(t));
      };
      auto tpa = [&](const Variant& v, int64_t N, int64_t M, bool frozen, bool ablation) {
        const int r = rep(v, N);
        Task t = plan.tasks[r];
        t.key = t.key.substr(0, t.key.size() - 3) + "tpa/M" + std::to_string(M) +
                (frozen ? "/frozen" : "/unfrozen");
        t.kind = TaskKind::tpa;
        t.M = M;
        t.frozen = frozen;
        t.deps = {r};
        const MlpShape net = tpa_network(phi, h, frozen);
        t.flops = kTestRewards * train_flops(net, 2 * M, h.tpa.epochs);
        t.bytes = kTestRewards * working_set(net, 2 * h.tpa.batch);
        Task& added = plan.tasks[add(std::move(t))];  // shared by both grids when keys match
        (ablation ? added.in_ablation : added.in_main) = true;
      };
      for (const auto& v : p.fpe_methods)
        for (int64_t N : axes.fpe_N) fpe(v, N);
      for (const auto& v : p.tpa.methods)
        for (int64_t N : axes.tpa_N)
          for (int64_t M : axes.tpa_M)
            for (bool fr : frozen_settings(p.tpa, v)) tpa(v, N, M, fr, false);
      for (Method m : p.ablation_methods)
        for (bool with_vae : {false, true}) {
          if (with_vae && !accepts_vae_pretrain(m)) continue;
          const Variant v{m, with_vae};
          for (int64_t N : axes.ablation_N)
            for (int64_t M : axes.ablation_M)
              for (bool fr : {true, false}) tpa(v, N, M, fr, true);
        }
    }
  }
  return plan;
}

}  // namespace sirl
