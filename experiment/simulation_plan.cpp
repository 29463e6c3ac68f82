// The paper's simulation grid (Fig. 4, 5 and 7, and [robustness]) expanded into its tasks:
// every environment × hyper-parameter point × seed × cell a profile asks for.
#include <cstdint>
#include <string>
#include <vector>

#include "engine/representation.h"
#include "experiment/profile.h"
#include "experiment/simulation_tasks.h"
#include "experiment/task_kinds.h"

namespace sirl {

namespace {

// A TPA cell of [tpa] (Fig. 5) or of [ablation] (Fig. 7); a cell both grids share is one task.
void add_tpa_cell(Plan& plan, const Profile& p, const std::string& env, int64_t seed,
                  const std::string& point, const Variant& v, int64_t N, int64_t M, bool frozen,
                  bool ablation) {
  Task t = experiment_cell(tpa_kind(), env, seed, v, N);
  t.hyper = point;
  t.M = M;
  t.frozen = frozen;
  Task& added = plan.tasks[size_t(add_task(plan, p, std::move(t)))];
  (ablation ? added.in_ablation : added.in_main) = true;
}

// A linear-evaluation cell of [tpa] (engine/linear_tpa.h): φ frozen, so one per (variant, N, M).
void add_linear_cell(Plan& plan, const Profile& p, const std::string& env, int64_t seed,
                     const std::string& point, const Variant& v, int64_t N, int64_t M) {
  Task t = experiment_cell(linear_tpa_kind(), env, seed, v, N);
  t.hyper = point;
  t.M = M;
  t.frozen = true;
  t.in_main = true;
  add_task(plan, p, std::move(t));
}

// The references (truth, raw) beside every method: their FPE where the environment has FPE
// cells; where it has [tpa] cells, truth under the paper's head and both under linear evaluation.
void add_reference_cells(Plan& plan, const Profile& p, const std::string& env, int64_t seed,
                         const std::string& point) {
  if (!p.references) return;
  const EnvAxes& axes = p.axes.at(env);
  for (Method m : {Method::truth, Method::raw}) {
    const Variant v{m};
    if (!p.fpe_methods.empty() && !axes.fpe_N.empty()) {
      Task t = experiment_cell(fpe_kind(), env, seed, v, 0);
      t.hyper = point;
      add_task(plan, p, std::move(t));
    }
    if (p.tpa.methods.empty() || axes.tpa_N.empty()) continue;
    for (int64_t M : axes.tpa_M) {
      // raw is a floor for linear evaluation only: the paper's 1024-wide head on the raw input
      // is a model of its own, not a reference for a representation.
      if (m == Method::truth && p.runs_protocol("paper"))
        add_tpa_cell(plan, p, env, seed, point, v, 0, M, true, false);
      if (p.runs_protocol("linear")) add_linear_cell(plan, p, env, seed, point, v, 0, M);
    }
  }
}

// [robustness]: every noisy teacher's cells, and the main teacher's cells of the same sizes
// (each axis's reference point; a cell the main grid has already is that task).
void add_robustness_cells(Plan& plan, const Profile& p, const std::string& env, int64_t seed,
                          const std::string& point) {
  const RobustnessGrid& g = p.robustness;
  if (g.teachers.empty()) return;
  auto at_point = [&](Task t) {
    t.hyper = point;
    return t;
  };
  for (const Variant& v : g.methods)
    for (int64_t N : g.N) {
      if (uses_queries(v.method))
        add_task(plan, p, at_point(experiment_cell(fpe_kind(), env, seed, v, N)));
      for (int64_t M : g.M)
        for (bool fr : frozen_settings(g, v)) {
          Task t = at_point(experiment_cell(tpa_kind(), env, seed, v, N));
          t.M = M;
          t.frozen = fr;
          add_task(plan, p, std::move(t));
        }
      for (const TeacherPoint& tp : g.teachers) {
        if (uses_queries(v.method))
          add_task(plan, p, at_point(experiment_cell(robust_fpe_kind(), env, seed, v, N, tp.tag)));
        for (int64_t M : g.M)
          for (bool fr : frozen_settings(g, v)) {
            Task t = at_point(experiment_cell(robust_tpa_kind(), env, seed, v, N, tp.tag));
            t.M = M;
            t.frozen = fr;
            add_task(plan, p, std::move(t));
          }
      }
    }
}

}  // namespace

void add_simulation_tasks(Plan& plan, const Profile& p) {
  for (const auto& env : p.envs) {
    const EnvAxes& axes = p.axes.at(env);
    // Every hyper-parameter point ("" = the base) runs the environment's whole grid; add_task
    // folds a task the point does not change into the base point's.
    for (const std::string& point : hyper_point_tags(p, env))
      for (int64_t seed : axes.seeds) {
        for (const auto& v : p.fpe_methods)
          for (int64_t N : axes.fpe_N)
            if (runs_in(p, v, env)) {
              Task t = experiment_cell(fpe_kind(), env, seed, v, N);
              t.hyper = point;
              add_task(plan, p, std::move(t));
            }
        for (const auto& v : p.tpa.methods)
          for (int64_t N : runs_in(p, v, env) ? axes.tpa_N : std::vector<int64_t>{})
            for (int64_t M : axes.tpa_M) {
              if (p.runs_protocol("paper"))
                for (bool fr : frozen_settings(p.tpa, v))
                  add_tpa_cell(plan, p, env, seed, point, v, N, M, fr, false);
              if (p.runs_protocol("linear")) add_linear_cell(plan, p, env, seed, point, v, N, M);
            }
        for (Method m : p.ablation_methods)
          for (bool with_vae : {false, true}) {
            if (with_vae && !accepts_vae_pretrain(m)) continue;
            const Variant v{m, with_vae};
            for (int64_t N : axes.ablation_N)
              for (int64_t M : axes.ablation_M)
                for (bool fr : {true, false})
                  add_tpa_cell(plan, p, env, seed, point, v, N, M, fr, true);
          }
        add_robustness_cells(plan, p, env, seed, point);
        add_reference_cells(plan, p, env, seed, point);
      }
  }
}

}  // namespace sirl
