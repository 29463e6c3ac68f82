#include <CLI/CLI.hpp>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "app/commands.h"
#include "jobs/mpi_run.h"

namespace sirl::app {

namespace {
// Single-quotes a path for /bin/sh.
std::string sh_quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}
}  // namespace

void register_reproduce(CLI::App& app, Runner& run) {
  auto* cmd = app.add_subcommand(
      "reproduce",
      "The main job: run a profile's whole grid (`sirl run`), then draw every figure of the paper\n"
      "and write the report from the results file (results/plot_figures.py, Debian's\n"
      "/usr/bin/python3 with h5py + matplotlib). Resumable: rerun after an interruption.");
  static std::string profile = "quick", out, figures;
  static int threads = 0;
  static bool force = false;
  cmd->add_option("--profile", profile, "Profile: smoke, quick, paper, or a .toml path")
      ->capture_default_str();
  cmd->add_option("--out", out, "Results file (default: results/<profile>.h5)");
  cmd->add_option("--figures", figures, "Figure directory (default: results/<profile>-figures)");
  cmd->add_option("--threads", threads, "Worker threads (default: every core)")
      ->check(CLI::Range(1, 4096));
  cmd->add_flag("--force", force, "Overwrite results from another profile or engine version");
  run = [] {
    const std::string stem = std::filesystem::path(profile).stem().string();
    if (out.empty()) out = "results/" + stem + ".h5";
    if (figures.empty()) figures = "results/" + stem + "-figures";
    const int rc = run_command(profile, out, threads, force, "", false);
    if (rc != 0 || mpi_rank_from_env() > 0) return rc;  // MPI workers do not plot
    const std::string script = std::string(SIRL_SOURCE_DIR) + "/results/plot_figures.py";
    if (!std::filesystem::exists(script))
      throw std::runtime_error("plotting script not found: " + script);
    const std::string command = "/usr/bin/python3 " + sh_quote(script) + " " + sh_quote(out) +
                                " --out " + sh_quote(figures);
    std::fprintf(stderr, "sirl reproduce: drawing figures: %s\n", command.c_str());
    const int status = std::system(command.c_str());
    if (status != 0) throw std::runtime_error("the plotting script failed (" + command + ")");
    std::printf("results: %s\nfigures: %s/\nreport:  %s/report.md\n", out.c_str(), figures.c_str(),
                figures.c_str());
    return 0;
  };
}

}  // namespace sirl::app
