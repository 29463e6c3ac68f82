#include "app/commands.h"
#include "jobs/slurm_submission.h"

#include <charconv>
#include <set>

#include "datasets/environments.h"
#include "datasets/study.h"
#include "experiment/profile.h"

#include <filesystem>

#include "results/h5.h"

#include <CLI/CLI.hpp>
#include <map>
#include <string>

namespace sirl::app {
namespace {
std::map<std::string, Runner>& runners() {
  static std::map<std::string, Runner> r;
  return r;
}
}  // namespace

namespace {

// Every integer option (CLI11 type INT or UINT) takes decimal digits only, without a sign or
// leading zeros: CLI11 alone reads "0x10" as 16, "010" as 8 and "-1" as 2⁶⁴ − 1 for an unsigned
// seed. Every real option (FLOAT) takes a plain decimal number ("0.5", "1e3"), never "nan",
// "0x1p3" or " 3"; the few that mean something by "inf" say so with positive_number().
bool has_validator(CLI::Option& o, const std::string& name) {
  try {
    o.get_validator(name);
    return true;
  } catch (const CLI::OptionNotFound&) {
    return false;
  }
}

void enforce_decimal_numbers(CLI::App& app) {
  for (CLI::Option* o : app.get_options()) {
    const std::string type = o->get_type_name();
    if (type.rfind("INT", 0) == 0 || type.rfind("UINT", 0) == 0)
      o->check(decimal_integer());
    else if (type.rfind("FLOAT", 0) == 0 && !has_validator(*o, "number"))
      o->check(decimal_number());
  }
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; }))
    enforce_decimal_numbers(*sub);
}

CLI::Validator number_check(const char* what, bool (*ok)(double), bool allow_inf) {
  return CLI::Validator(
      [what, ok, allow_inf](std::string& v) -> std::string {
        if (allow_inf && v == "inf") return "";
        double x = 0;
        const auto [p, ec] = std::from_chars(v.data(), v.data() + v.size(), x);
        const bool parsed = ec == std::errc() && p == v.data() + v.size();
        if (!is_decimal_number(v) || !parsed || !ok(x))
          return std::string("must be ") + what + ", got '" + v + "'";
        return "";
      },
      "NUMBER", "number");
}

}  // namespace

bool is_decimal_integer(const std::string& v) {
  return !v.empty() && v.size() <= 19 && v.find_first_not_of("0123456789") == std::string::npos &&
         (v[0] != '0' || v.size() == 1);
}

bool is_decimal_number(const std::string& v) {
  size_t i = 0;
  auto digits = [&] {
    const size_t from = i;
    while (i < v.size() && v[i] >= '0' && v[i] <= '9') ++i;
    return i - from;
  };
  if (i < v.size() && v[i] == '-') ++i;
  const size_t first = i, whole = digits();
  if (whole == 0 || (whole > 1 && v[first] == '0')) return false;  // "", ".5", "010"
  if (i < v.size() && v[i] == '.') {
    ++i;
    if (digits() == 0) return false;  // "3."
  }
  if (i < v.size() && (v[i] == 'e' || v[i] == 'E')) {
    ++i;
    if (i < v.size() && (v[i] == '+' || v[i] == '-')) ++i;
    if (digits() == 0) return false;
  }
  return i == v.size();
}

CLI::Validator decimal_integer() {
  return CLI::Validator(
      [](std::string& v) -> std::string {
        if (!is_decimal_integer(v))
          return "must be a non-negative decimal integer (digits, no leading zero), got '" + v +
                 "'";
        return "";
      },
      "DECIMAL", "decimal");
}

CLI::Validator decimal_number() {
  return CLI::Validator(
      [](std::string& v) -> std::string {
        if (!is_decimal_number(v))
          return "must be a decimal number (e.g. 0.5, 2, 1e3), got '" + v + "'";
        return "";
      },
      "DECIMAL", "decimal");
}

CLI::Validator output_file() {
  return CLI::Validator(
      [](std::string& v) -> std::string {
        std::error_code ec;
        if (v.empty()) return "must name a file, got an empty path";
        if (v.back() == '/' || std::filesystem::is_directory(v, ec))
          return "must name a file, got the folder '" + v + "'";
        // A FIFO or device would block the write forever, or never hold a results file.
        const auto st = std::filesystem::status(v, ec);
        if (!ec && std::filesystem::exists(st) && !std::filesystem::is_regular_file(st))
          return "must name a regular file, got '" + v + "' (a pipe, socket or device)";
        return "";
      },
      "FILE", "output_file");
}

CLI::Validator positive_number() {
  return number_check(
      "a number > 0 (inf allowed)", [](double x) { return x > 0; }, true);
}

CLI::Validator non_negative_number() {
  return number_check(
      "a number >= 0", [](double x) { return x >= 0; }, false);
}

std::vector<std::string>& profile_settings() {
  static std::vector<std::string> settings;
  return settings;
}

void add_set_option(CLI::App* cmd) {
  cmd->add_option("--set", profile_settings(),
                  "Set one profile value for this run, KEY=VALUE with VALUE in TOML, KEY dotted "
                  "(repeatable, applied in order on top of the profile and its parents): "
                  "--set seeds=[0,1] --set 'hyper.grid.\"sirl.epochs\"=100' --set "
                  "jaco.trajectories=2000. The results file records the resolved profile")
      ->type_name("KEY=VALUE")
      ->allow_extra_args(false);
}

CacheChoice& cache_choice() {
  static CacheChoice c;
  return c;
}

void add_cache_options(CLI::App* cmd) {
  cmd->add_option("--cache", cache_choice().dir,
                  "The task cache: finished tasks filed by what they depend on, reused by any "
                  "run given this folder whatever else its profile changed (default: OUT.tasks "
                  "beside the output). Runs may share one at once; `sirl gc` trims it")
      ->type_name("DIR");
  cmd->add_flag("--any-cpu-class", cache_choice().any_cpu_class,
                "Reuse results the cache holds from another CPU class (other bits) when this "
                "class has none; /tables/timings' cpu_class column says which class computed "
                "each task");
}

void register_all(CLI::App& app) {
  register_version(app, runners()["version"]);
  register_reproduce(app, runners()["reproduce"]);
  register_dataset(app, runners()["dataset"]);
  register_inspect(app, runners()["inspect"]);
  register_render(app, runners()["render"]);
  register_study(app, runners()["study"]);
  register_plan(app, runners()["plan"]);
  register_run(app, runners()["run"]);
  register_export(app, runners()["export"]);
  register_merge(app, runners()["merge"]);
  register_evaluate(app, runners()["evaluate"]);
  register_gc(app, runners()["gc"]);
  register_submit(app, runners()["submit"]);
  register_status(app, runners()["status"]);
  register_show(app, runners()["show"]);
  enforce_decimal_numbers(app);
}

int run_selected(CLI::App& app) {
  for (auto* sub : app.get_subcommands()) {
    auto it = runners().find(sub->get_name());
    if (it != runners().end() && it->second) return it->second();
  }
  return 2;
}

void check_replaceable(const std::string& out, const std::string& kind, bool force) {
  std::error_code ec;
  if (force || !std::filesystem::exists(out, ec)) return;
  std::string holds;
  try {
    const H5File f = H5File::open_read(out);
    const bool runs = f.exists("/runs_index"), study = f.exists("/study"),
               data = f.exists("/datasets");
    if (kind == "dataset" && data && !runs && !study) return;
    if (kind == "study" && study) return;
    holds = runs    ? "a results file"
            : study ? "a study file"
            : data  ? "a dataset file"
                    : "another HDF5 file";
  } catch (const H5Error&) {
    holds = "a file that is not HDF5";
  }
  throw UsageError(out + " already exists and is " + holds + ", not a " + kind +
                   " file; choose another --out, or --force to replace it");
}

uint64_t folder_bytes(const std::filesystem::path& dir) {
  uint64_t total = 0;
  std::error_code ec;
  for (auto it = std::filesystem::recursive_directory_iterator(dir, ec);
       !ec && it != std::filesystem::recursive_directory_iterator(); it.increment(ec))
    if (it->is_regular_file(ec) && !it->is_symlink(ec)) total += it->file_size(ec);
  return total;
}

std::string sh_quote(const std::string& s) {
  return shell_quoted(s);
}

std::vector<std::string> env_choices() {
  std::vector<std::string> v;
  for (const auto& e : environments()) v.push_back(e.name);
  return v;
}

std::string study_env_help() {
  return "Environment: " + study_env_names() +
         " (jaco2 is the paper's),\nor one --profile declares from a file with 2-D points";
}

void declare_profile_environments(const std::string& profile) {
  if (profile.empty()) return;
  try {
    load_profile(profile, {});
  } catch (const ProfileError& e) {
    throw UsageError(e.what());
  }
}

}  // namespace sirl::app
