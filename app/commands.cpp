#include "app/commands.h"

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
