// `sirl gc`: trims a task cache to what the given profiles need.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <set>
#include <string>
#include <vector>

#include "app/commands.h"
#include "experiment/plan.h"
#include "experiment/profile.h"
#include "experiment/task_digest.h"
#include "jobs/task_cache.h"

namespace sirl::app {

namespace {

std::string mib(uint64_t bytes) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f MiB", double(bytes) / (1024.0 * 1024.0));
  return buf;
}

}  // namespace

void register_gc(CLI::App& app, Runner& run) {
  auto* cmd = app.add_subcommand(
      "gc",
      "Remove from a task cache (sirl run --cache DIR, or OUT.tasks) every result and training\n"
      "checkpoint that none of the given profiles needs. What a running `sirl run` needs or is\n"
      "computing is always kept. --set applies to every profile given.");
  static std::string dir;
  static std::vector<std::string> profiles;
  static bool dry_run = false, all = false;
  cmd->add_option("cache", dir, "The cache folder")->required()->check(CLI::ExistingDirectory);
  cmd->add_option("profiles", profiles,
                  "Profiles whose tasks to keep: names in configs/ (" + bundled_profile_names() +
                      ") or .toml paths");
  cmd->add_flag("--all", all, "Keep no profile's tasks (only what running processes hold)");
  cmd->add_flag("--dry-run", dry_run, "Say what would be removed, remove nothing");
  add_set_option(cmd);
  run = [] {
    if (profiles.empty() && !all)
      throw UsageError("name the profiles whose tasks to keep, or --all to keep none");
    if (!profiles.empty() && all) throw UsageError("--all keeps no profile: give one or the other");
    std::set<std::string> keep;
    for (const std::string& name : profiles) {
      Profile p;
      try {
        p = load_profile(name, profile_settings());
      } catch (const ProfileError& e) {
        throw UsageError(e.what());
      }
      for (const std::string& d : task_digests(make_plan(p))) keep.insert(d);
    }
    const GcSummary s = collect_garbage(dir, keep, dry_run);
    std::printf("sirl gc: %s %lld results and checkpoints (%s); kept %lld (%s)",
                dry_run ? "would remove" : "removed", static_cast<long long>(s.removed),
                mib(s.removed_bytes).c_str(), static_cast<long long>(s.kept),
                mib(s.kept_bytes).c_str());
    if (s.held > 0)
      std::printf(", %lld of them for a running sirl run", static_cast<long long>(s.held));
    std::printf("\n");
    return 0;
  };
}

}  // namespace sirl::app
