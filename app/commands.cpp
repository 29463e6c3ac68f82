#include "app/commands.h"

#include <charconv>
#include <set>

#include "datasets/environments.h"

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

// Options that take a count, a seed or a port: decimal digits only. CLI11 alone reads "0x10" as
// 16 and "-1" as 2⁶⁴ − 1 for an unsigned seed.
const std::set<std::string> kIntegerOptions{
    "--threads",    "--seed",       "--trajectories", "--users",   "--similarity",
    "--preference", "--tpa-pairs",  "--fpe",          "--seeds",   "--splits",
    "--epochs",     "--tpa-epochs", "--port",         "--practice"};

void enforce_decimal_integers(CLI::App& app) {
  for (CLI::Option* o : app.get_options())
    if (kIntegerOptions.count(o->get_name())) o->check(decimal_integer());
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; }))
    enforce_decimal_integers(*sub);
}

CLI::Validator number_check(const char* what, bool (*ok)(double)) {
  return CLI::Validator(
      [what, ok](std::string& v) -> std::string {
        double x = 0;
        const auto [p, ec] = std::from_chars(v.data(), v.data() + v.size(), x);
        const bool parsed = ec == std::errc() && p == v.data() + v.size();
        if (v == "inf" || v == "infinity") return "";
        if (!parsed || !ok(x)) return std::string("must be ") + what + ", got '" + v + "'";
        return "";
      },
      "NUMBER");
}

}  // namespace

CLI::Validator decimal_integer() {
  return CLI::Validator(
      [](std::string& v) -> std::string {
        if (v.empty() || v.size() > 19 || v.find_first_not_of("0123456789") != std::string::npos)
          return "must be a non-negative decimal integer, got '" + v + "'";
        return "";
      },
      "INT");
}

CLI::Validator positive_number() {
  return number_check("a number > 0 (inf allowed)", [](double x) { return x > 0; });
}

CLI::Validator non_negative_number() {
  return number_check("a number >= 0", [](double x) { return x >= 0; });
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
  enforce_decimal_integers(app);
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

std::string sh_quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::vector<std::string> env_choices() {
  std::vector<std::string> v;
  for (const auto& e : environments()) v.push_back(e.name);
  return v;
}

std::vector<std::string> study_env_choices() {
  std::vector<std::string> v;
  for (const auto& e : environments())
    if (e.in_study) v.push_back(e.name);
  return v;
}

}  // namespace sirl::app
