// Registry of the `sirl` subcommands. Each cmd_*.cpp defines one `register_*` function that
// adds its CLI11 subcommand and sets `callback` (run after a successful parse).
#pragma once
#include <cstdint>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "engine/study_analysis.h"

namespace sirl {
struct Profile;
}
namespace CLI {
class App;
class Validator;
}  // namespace CLI

namespace sirl::app {

// A bad value found after parsing (e.g. a file that does not exist): exit code 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

using Runner = std::function<int()>;

void register_version(CLI::App& app, Runner& run);
void register_reproduce(CLI::App& app, Runner& run);
void register_dataset(CLI::App& app, Runner& run);
void register_inspect(CLI::App& app, Runner& run);
void register_render(CLI::App& app, Runner& run);
void register_study(CLI::App& app, Runner& run);
void register_run(CLI::App& app, Runner& run);
void register_plan(CLI::App& app, Runner& run);
void register_export(CLI::App& app, Runner& run);
void register_merge(CLI::App& app, Runner& run);
void register_gc(CLI::App& app, Runner& run);
void register_submit(CLI::App& app, Runner& run);
void register_status(CLI::App& app, Runner& run);
void register_show(CLI::App& app, Runner& run);
void register_evaluate(CLI::App& app, Runner& run);

// The `--set KEY=VALUE` overrides of the command being run (experiment/profile.h, load_profile),
// and the option that fills them, for every command that takes a profile.
std::vector<std::string>& profile_settings();
void add_set_option(CLI::App* cmd);

// Single-quotes a string for /bin/sh (the plotting scripts are run through std::system).
std::string sh_quote(const std::string& s);
// Σ sizes of the regular files under dir, links not followed (0 when absent): a task cache's size.
uint64_t folder_bytes(const std::filesystem::path& dir);

// Before a command replaces `out`: an existing file must be one this command writes (`kind`:
// "dataset" has /datasets and no /runs_index or /study; "study" has /study), else it is refused
// with a UsageError naming what it holds, unless `force`. Never replaces a file silently.
void check_replaceable(const std::string& out, const std::string& kind, bool force);

// Validators with one readable line ("must be a number > 0, got '-1'") instead of CLI11's
// ranges that print DBL_MAX in full; decimal_integer refuses "0x10", "010", "-1", " 3", "+3";
// decimal_number refuses those and "nan", "inf", "3.", ".5" (positive_number accepts "inf").
// register_all puts one of the two on every integer and real option.
bool is_decimal_integer(const std::string& v);
bool is_decimal_number(const std::string& v);
CLI::Validator decimal_integer();
CLI::Validator decimal_number();
// An output file's path: not empty, not an existing folder, not ending in '/'.
CLI::Validator output_file();
CLI::Validator positive_number();
CLI::Validator non_negative_number();

// Environment names for `--env` choices: every registered one, or those the study may use.
std::vector<std::string> env_choices();
// The study commands' --env help: the built-in study environments, and a profile's from files.
std::string study_env_help();
// `sirl study … --profile P`: reads P so the environments it declares from files
// ([environments.<name>]) are registered and a study can run on them. Nothing for "".
void declare_profile_environments(const std::string& profile);

// This build's version and git commit (recorded in every results file).
const char* engine_version();
const char* git_commit();

// `sirl study simulate` and `sirl study analyze` proper, shared with `sirl reproduce`.
int study_simulate(const std::string& env, int64_t trajectories, int users, int64_t n_sim,
                   int64_t n_pref, double beta, double mistake, uint64_t seed,
                   const std::string& out, bool force = false);
int study_analyze(const std::string& file, const std::string& out, int seeds, int splits,
                  int epochs, int tpa_epochs, int threads, bool random_frozen = false);
// The analysis file (OUT/study_analysis.h5), then Fig. 6 and study_report.md from it.
void write_study_analysis(const std::string& study_file, const std::string& env,
                          const StudyAnalysis& a, const StudyAnalysisConfig& c,
                          const std::string& out);
// Fig. 6 and OUT/study_report.md (report/plot_study.py) from a study analysis: the file
// `sirl study analyze` writes, or a results file whose profile ran the study (/tables/study;
// study_file names where its answers were written).
void plot_study(const std::string& analysis, const std::string& out,
                const std::string& study_file = "");

// --cache DIR and --any-cpu-class (jobs/run.h's RunOptions), shared by the commands that run
// or plan a profile.
struct CacheChoice {
  std::string dir;  // "" = OUT.tasks
  bool any_cpu_class = false;
};
CacheChoice& cache_choice();
void add_cache_options(CLI::App* cmd);

// `sirl run` proper, shared with `sirl reproduce`.
// `skip_study` leaves the profile's [study] tasks out of the plan (`sirl reproduce --no-study`).
int run_command(const std::string& profile, const std::string& out, int threads, bool force,
                const std::string& shard, bool quiet, bool skip_study = false,
                double checkpoint_minutes = 5, int max_task_threads = 0);

// The same for a profile already loaded (`sirl evaluate` adds its [external] section first).
int run_loaded_profile(Profile p, const std::string& out, int threads, bool force,
                       const std::string& shard, bool quiet, bool skip_study = false,
                       double checkpoint_minutes = 5, int max_task_threads = 0);
// Draws every figure and writes the report of a results file into `figures`
// (report/plot_figures.py through Debian's python3); throws std::runtime_error if it fails.
void draw_figures(const std::string& results, const std::string& figures);

void register_all(CLI::App& app);
int run_selected(CLI::App& app);

}  // namespace sirl::app
