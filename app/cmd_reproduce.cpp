#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "app/cluster_options.h"
#include "app/commands.h"
#include "experiment/install_paths.h"
#include "experiment/plan.h"
#include "experiment/profile.h"
#include "jobs/estimate.h"
#include "jobs/mpi_run.h"
#include "jobs/progress.h"
#include "jobs/run.h"
#include "results/results_file.h"
#include "results/study_store.h"

namespace sirl::app {

void draw_figures(const std::string& results, const std::string& figures) {
  const std::string script = (data_dir() / "report" / "plot_figures.py").string();
  if (!std::filesystem::exists(script))
    throw std::runtime_error("plotting script not found: " + script);
  const std::string command = sh_quote(python_interpreter()) + " " + sh_quote(script) + " " +
                              sh_quote(results) + " --out " + sh_quote(figures);
  std::fprintf(stderr, "sirl: drawing figures: %s\n", command.c_str());
  const int status = std::system(command.c_str());
  if (status != 0) throw std::runtime_error("the plotting script failed (" + command + ")");
}

// The verdicts the report decided (FIGURES/claims.json) kept in the results file itself
// (/verdicts: `sirl show`, sirl_bench's Results.verdicts()), so the file carries its verdicts
// wherever it is copied. A claims.json that is not the report's list is refused.
void store_report_verdicts(const std::string& results, const std::string& figures) {
  const std::filesystem::path claims = std::filesystem::path(figures) / "claims.json";
  std::ifstream in(claims);
  if (!in) throw std::runtime_error(claims.string() + ": the report wrote no verdicts");
  const nlohmann::json all = nlohmann::json::parse(in, nullptr, false);
  if (!all.is_array())
    throw std::runtime_error(claims.string() + ": not the report's list of verdicts");
  store_verdicts(
      results, all.dump(),
      "report/plot_figures.py (sirl reproduce, engine " + std::string(engine_version()) + ")");
  std::fprintf(stderr, "sirl reproduce: %zu verdicts stored in %s (/verdicts)\n", all.size(),
               results.c_str());
}

// Before a run of a profile with a budget (budget_minutes): what `sirl plan` predicts on this
// machine, and a warning naming the smallest profile when that is well over the budget (the
// budget is set on one CPU class; without AVX-512 a run takes two to three times as long).
// Only the tasks the cache (--cache, or OUT.tasks) does not hold are predicted, unless --force
// recomputes them all. Returns the predicted seconds, or -1 when nothing was predicted.
double announce_prediction(const Profile& p, int threads, const std::string& out, bool force) {
  if (p.budget_minutes <= 0) return -1;
  const int th = threads > 0 ? threads : default_threads();
  const Plan plan = make_plan(p);
  std::vector<char> pending(plan.tasks.size(), 1);
  const std::filesystem::path cache =
      std::filesystem::path(cache_choice().dir.empty() ? out + ".tasks" : cache_choice().dir);
  std::error_code ec;
  if (!force && std::filesystem::is_directory(cache, ec)) {
    const CacheHoldings h = cache_holdings(plan, p, cache);
    if (size_t(h.tasks) == plan.tasks.size()) {
      std::fprintf(stderr,
                   "sirl reproduce: all %zu tasks of %s are in the cache %s: nothing to compute\n",
                   plan.tasks.size(), p.name.c_str(), cache.c_str());
      return 0;
    }
    for (size_t i = 0; i < pending.size(); ++i) pending[i] = !h.held[i];
    if (h.tasks > 0)
      std::fprintf(stderr, "sirl reproduce: %d of %zu tasks are in the cache %s\n", h.tasks,
                   plan.tasks.size(), cache.c_str());
  }
  std::fprintf(stderr, "sirl reproduce: predicting the time on this machine (sirl plan %s)...\n",
               p.name.c_str());
  const PlanEstimate e = estimate_plan(plan, p, th, pending);
  const double budget = 60.0 * double(p.budget_minutes);
  std::fprintf(
      stderr, "sirl reproduce: %s is predicted to take %s on %d thread(s) here (its budget: %s)\n",
      p.name.c_str(), format_duration(e.seconds).c_str(), th, format_duration(budget).c_str());
  if (const std::string busy = busy_machine_note(e, th); !busy.empty())
    std::fprintf(stderr, "sirl reproduce: note: %s\n", busy.c_str());
  if (e.seconds > 1.5 * budget)
    std::fprintf(stderr,
                 "sirl reproduce: warning: that is %.1fx %s's budget on this machine; `sirl "
                 "reproduce --profile smoke` runs the whole pipeline at toy scale in under a "
                 "minute, and `sirl run` resumes if you stop this one (Ctrl-C)\n",
                 e.seconds / budget, p.name.c_str());
  return e.seconds;
}

void register_reproduce(CLI::App& app, Runner& run) {
  auto* cmd = app.add_subcommand(
      "reproduce",
      "The main job: run a profile's whole grid (`sirl run`), then draw every figure of the paper\n"
      "and write the report from the results file (report/plot_figures.py, Debian's\n"
      "/usr/bin/python3 with h5py + matplotlib). Resumable: rerun after an interruption.");
  static std::string profile = "quick", out, figures;
  static int threads = 0;
  static bool force = false, no_study = false;
  cmd->add_option("profile,--profile", profile,
                  "Profile: a name in configs/ (" + bundled_profile_names() + ") or a .toml path")
      ->capture_default_str();
  cmd->add_option("--out", out, "Results file (default: out/<profile>.h5)")->check(output_file());
  cmd->add_option("--figures", figures,
                  "Figure directory (default: beside the results file, <out stem>-figures)");
  cmd->add_option("--threads", threads, "Worker threads (default: every core)")
      ->check(CLI::Range(1, 4096));
  cmd->add_flag("--force", force, "Overwrite results from another profile or engine version");
  cmd->add_flag("--no-study", no_study, "Skip the simulated user study (Fig. 6)");
  add_set_option(cmd);
  add_cache_options(cmd);
  run = [] {
    const std::string stem = std::filesystem::path(profile).stem().string();
    // out/ (git-ignored; run_command makes it) is the default home of results; the figures go
    // beside the results file (out/quick.h5 → out/quick-figures/).
    if (out.empty()) out = "out/" + stem + ".h5";
    if (figures.empty()) {
      const std::filesystem::path o(out);
      figures = (o.parent_path() / (o.stem().string() + "-figures")).string();
    }
    const Profile p = load_profile(profile, profile_settings());
    const double predicted =
        mpi_rank_from_env() <= 0 ? announce_prediction(p, threads, out, force) : -1;
    const auto t0 = std::chrono::steady_clock::now();
    const int rc = run_command(profile, out, threads, force, "", false, no_study);
    if (rc != 0 || mpi_rank_from_env() > 0) return rc;  // MPI workers do not plot
    const auto t1 = std::chrono::steady_clock::now();
    draw_figures(out, figures);
    store_report_verdicts(out, figures);
    // The user-study pipeline on a simulated cohort (Fig. 6), when the profile asks for it.
    std::string study_line;
    if (p.study.enabled && !no_study) {
      // The study ran as tasks of the plan, its analysis too (/tables/study): here Fig. 6 and
      // study_report.md are drawn from the results file, beside the cohort's answers as a study
      // file (what `sirl study analyze` or the study server read).
      const std::string dir = figures + "/study", file = dir + "/simulated_study.h5";
      std::filesystem::create_directories(dir);
      std::fprintf(stderr, "sirl reproduce: user study (%d simulated users, %s)\n",
                   p.study.cohort.users, p.study.cohort.env.c_str());
      write_study(file, simulate_cohort(p.study.cohort));
      plot_study(out, dir, file);
      study_line = "study:   " + dir + "/study_report.md (Fig. 6: " + dir + "/fig6_study.png)\n";
    }
    const auto seconds = [](auto a, auto b) {
      return std::chrono::duration<double>(b - a).count();
    };
    const auto t2 = std::chrono::steady_clock::now();
    std::fprintf(stderr, "sirl reproduce: the run took %s%s; figures and report %s\n",
                 format_duration(seconds(t0, t1)).c_str(),
                 predicted >= 0 ? (" (predicted " + format_duration(predicted) + ")").c_str() : "",
                 format_duration(seconds(t1, t2)).c_str());
    std::printf("results: %s\nfigures: %s/\nreport:  %s/report.md\n%s", out.c_str(),
                figures.c_str(), figures.c_str(), study_line.c_str());
    return 0;
  };
}

}  // namespace sirl::app
