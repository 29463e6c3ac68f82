// `sirl show FILE.h5 [--json]`: what a results file holds, in one screen: the profile and its
// scale, the engine, CPU class and machine that wrote it, how much of the plan is done, its
// environments and task kinds, the claims' verdicts (stored in the file, or from the report beside
// it), and the files beside it. Read-only; the file is untrusted input (read as every command reads
// it).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "app/commands.h"
#include "experiment/profile.h"
#include "results/results_file.h"

namespace sirl::app {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// The main claims' verdicts of a list the report writes (claims.json, or /verdicts@claims in
// the results file), or null when it is not such a list.
json main_verdicts(const json& all) {
  if (!all.is_array()) return nullptr;
  json out = json::array();
  for (const json& h : all) {
    // Fields of another type than the report writes are read as absent, never thrown on.
    const auto flag = [&](const char* k) {
      return h.contains(k) && h[k].is_boolean() && h[k].get<bool>();
    };
    if (!h.is_object() || !flag("main")) continue;
    const auto text = [&](const char* k) {
      return h.contains(k) && h[k].is_string() ? h[k].get<std::string>() : std::string();
    };
    out.push_back({{"env", text("env")},
                   {"claim", text("claim")},
                   {"protocol", text("protocol")},
                   {"verdict", text("verdict")},
                   {"beyond_paper", flag("beyond_paper")}});
  }
  return out;
}

json describe(const std::string& file) {
  const ResultsSummary summary = read_results_summary(file);
  const RunInfo& info = summary.info;
  json j;
  j["file"] = file;
  j["verified"] = info.verified;
  j["schema_version"] = info.schema_version;
  j["profile"] = info.profile_name;
  // The profile the file records: its description and scale (a text that does not parse is
  // said, not fatal: the rest of the file is still described).
  try {
    const Profile p = parse_profile(info.profile_text, file + "@profile_text");
    j["description"] = p.description;
    j["environments"] = p.envs;
    j["seeds"] = p.seeds;
  } catch (const std::exception& e) {
    j["profile_error"] = e.what();
  }
  j["engine"] = {{"version", info.engine_version}, {"commit", info.git_commit}};
  j["cpu_class"] = info.cpu_class;
  j["host"] = info.host;
  j["threads"] = info.threads;
  j["started"] = info.started;
  j["finished"] = info.finished;
  j["wall_seconds"] = info.wall_seconds;
  j["shard"] = info.shard;
  j["tasks"] = {
      {"done", info.tasks_done}, {"total", info.tasks_total}, {"complete", info.complete}};
  j["task_kinds"] = summary.records_by_kind;
  const fs::path path(file);
  const fs::path figures = path.parent_path() / (path.stem().string() + "-figures");
  json beside = json::object();
  std::error_code ec;
  if (fs::is_regular_file(file + ".sum", ec)) beside["checksum"] = file + ".sum";
  if (fs::is_directory(file + ".tasks", ec))
    beside["task_cache"] = {{"path", file + ".tasks"}, {"bytes", folder_bytes(file + ".tasks")}};
  if (fs::is_directory(figures, ec)) {
    beside["figures"] = figures.string();
    if (fs::is_regular_file(figures / "report.md", ec))
      beside["report"] = (figures / "report.md").string();
  }
  j["beside"] = beside;
  // The verdicts stored in the file (`sirl reproduce` stores them), else those of a report
  // beside it (report/plot_figures.py run by hand).
  j["verdicts"] = nullptr;
  if (!summary.verdicts.empty()) {
    j["verdicts"] = main_verdicts(json::parse(summary.verdicts, nullptr, false));
    if (!j["verdicts"].is_null()) j["verdicts_from"] = file + " (/verdicts)";
  }
  if (j["verdicts"].is_null()) {
    std::ifstream in(figures / "claims.json");
    if (in) j["verdicts"] = main_verdicts(json::parse(in, nullptr, false));
    if (!j["verdicts"].is_null()) j["verdicts_from"] = (figures / "claims.json").string();
  }
  return j;
}

// A text field for the terminal: the file's bytes are not ours to print, so control characters
// (escapes, line breaks) become '?'.
std::string str(const json& j, const char* k) {
  std::string s = j.contains(k) && j[k].is_string() ? j[k].get<std::string>() : std::string();
  for (char& c : s)
    if ((c >= 0 && c < 0x20) || c == 0x7f) c = '?';
  return s;
}

void print_text(const json& j) {
  std::printf("%s: profile %s%s\n", str(j, "file").c_str(), str(j, "profile").c_str(),
              j["verified"].get<bool>() ? "" : "  (no checksum verified it)");
  if (!str(j, "description").empty()) std::printf("  %s\n", str(j, "description").c_str());
  if (j.contains("environments")) {
    std::string envs;
    for (const auto& e : j["environments"])
      envs += (envs.empty() ? "" : ", ") + e.get<std::string>();
    std::printf("environments: %s   seeds: %zu\n", envs.c_str(), j["seeds"].size());
  }
  if (j.contains("profile_error"))
    std::printf("profile text: cannot be read (%s)\n", str(j, "profile_error").c_str());
  const json& t = j["tasks"];
  std::printf("tasks: %lld of %lld done%s%s\n", static_cast<long long>(t["done"].get<int64_t>()),
              static_cast<long long>(t["total"].get<int64_t>()),
              t["complete"].get<bool>() ? " (complete)" : " (INCOMPLETE)",
              str(j, "shard").empty() ? "" : (", shard " + str(j, "shard")).c_str());
  std::string kinds;
  for (const auto& [k, n] : j["task_kinds"].items())
    kinds += (kinds.empty() ? "" : ", ") + k + " " + std::to_string(n.get<int64_t>());
  std::printf("  by kind: %s\n", kinds.c_str());
  std::printf("written by: engine %s (commit %s) on %s, %lld thread(s), %s → %s (%.0f s)\n",
              str(j["engine"], "version").c_str(), str(j["engine"], "commit").c_str(),
              str(j, "host").c_str(), static_cast<long long>(j["threads"].get<int64_t>()),
              str(j, "started").c_str(), str(j, "finished").c_str(),
              j["wall_seconds"].get<double>());
  std::printf("CPU class: %s\n", str(j, "cpu_class").c_str());
  if (j["verdicts"].is_array()) {
    std::printf("main claims (%s):\n", str(j, "verdicts_from").c_str());
    for (const json& v : j["verdicts"])
      std::printf("  %-5s %-7s %-13s %s%s\n", str(v, "env").c_str(),
                  str(v, "protocol").empty() ? "-" : str(v, "protocol").c_str(),
                  str(v, "verdict").c_str(), str(v, "claim").c_str(),
                  v["beyond_paper"].get<bool>() ? "  (beyond the paper)" : "");
  } else {
    std::printf(
        "main claims: no report beside it (`sirl reproduce`, or report/plot_figures.py "
        "FILE --out DIR, writes one)\n");
  }
  const json& b = j["beside"];
  if (b.contains("report")) std::printf("report: %s\n", str(b, "report").c_str());
  if (b.contains("task_cache"))
    std::printf("task cache: %s (%.0f MiB)\n", str(b["task_cache"], "path").c_str(),
                double(b["task_cache"]["bytes"].get<uint64_t>()) / (1 << 20));
}

}  // namespace

void register_show(CLI::App& app, Runner& run) {
  auto* cmd = app.add_subcommand(
      "show",
      "Summarise a results file: its profile and scale, the engine, CPU class and machine that "
      "wrote it, the tasks done, the main claims' verdicts (stored in the file by sirl reproduce, "
      "or from the report beside it) and the "
      "files beside it. --json for scripts.");
  static std::string file;
  static bool as_json = false;
  cmd->add_option("file", file, "Results file (HDF5)")->required()->check(CLI::ExistingFile);
  cmd->add_flag("--json", as_json, "Print one JSON object instead");
  run = [] {
    const json j = describe(file);
    if (as_json)
      std::printf("%s\n", j.dump(1, ' ', false, json::error_handler_t::replace).c_str());
    else
      print_text(j);
    return 0;
  };
}

}  // namespace sirl::app
