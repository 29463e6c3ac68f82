#include <CLI/CLI.hpp>
#include <cstdio>
#include <string>

#include "app/commands.h"

namespace sirl::app {

void register_reproduce(CLI::App& app, Runner& run) {
  auto* cmd = app.add_subcommand(
      "reproduce",
      "Run a profile's whole grid and draw every figure of the paper (the main job).\n"
      "Today: the batch engine has not landed yet; the command says so and exits.");
  static std::string profile = "quick";
  static std::string out = "results/quick.h5";
  cmd->add_option("--profile", profile, "Profile name in configs/ (smoke, quick, paper)")
      ->check(CLI::IsMember({"smoke", "quick", "paper"}))
      ->capture_default_str();
  cmd->add_option("--out", out, "HDF5 results file")->capture_default_str();
  run = [] {
    std::printf(
        "sirl reproduce --profile %s --out %s\n"
        "The batch engine (profiles, task DAG, figures) has not landed yet: nothing to run.\n"
        "What works today: `sirl version`, and the kernels' tests (`ctest --preset release`).\n",
        profile.c_str(), out.c_str());
    return 0;
  };
}

}  // namespace sirl::app
