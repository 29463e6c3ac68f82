#include <CLI/CLI.hpp>
#include <Eigen/Core>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "app/commands.h"
#include "build_info.h"
#include "jobs/provenance.h"
#include "kernels/gemm_bf16.h"
#include "probes/cpu_class.h"
#include "probes/roofline.h"
#include "results/results_file.h"

namespace sirl::app {

const char* engine_version() {
  return SIRL_VERSION;
}
const char* git_commit() {
  return SIRL_GIT_COMMIT;
}

void register_version(CLI::App& app, Runner& run) {
  auto* cmd = app.add_subcommand("version",
                                 "Print the version, git commit, compiler and flags of this "
                                 "build, the CPU class results depend on and this core's measured "
                                 "fp32 roof");
  static bool as_json = false;
  cmd->add_flag("--json", as_json, "Print one JSON object instead (for nightly scripts)");
  run = [] {
    if (as_json) {
      nlohmann::json j;
      j["version"] = SIRL_VERSION;
      j["commit"] = SIRL_GIT_COMMIT;
      j["results_schema"] = kResultsSchemaVersion;
      j["build"] = SIRL_BUILD_TYPE;
      j["compiler"] = SIRL_CXX_COMPILER;
      j["flags"] = SIRL_CXX_FLAGS;
      for (const auto& [name, version] : library_versions()) j["libraries"][name] = version;
      j["cpu_class"] = cpu_class();
      j["kernels"] = kernel_paths();
      j["bf16"] = bf16_backend();
      j["fp32_roof_gflops_per_core"] = fp32_roof_gflops_per_core();
      j["bf16_roof_gflops_per_core"] = bf16_roof_gflops_per_core();
      std::printf("%s\n", j.dump(1, ' ', false, nlohmann::json::error_handler_t::replace).c_str());
      return 0;
    }
    std::printf("sirl-bench %s\n", SIRL_VERSION);
    std::printf("commit:    %s\n", SIRL_GIT_COMMIT);
    std::printf("results:   schema version %lld (reads 1 to %lld)\n",
                (long long)kResultsSchemaVersion, (long long)kResultsSchemaVersion);
    std::printf("build:     %s\n", SIRL_BUILD_TYPE);
    std::printf("compiler:  %s\n", SIRL_CXX_COMPILER);
    std::printf("flags:     %s\n", SIRL_CXX_FLAGS);
    std::printf("eigen:     %d.%d.%d (SIMD: %s)\n", EIGEN_WORLD_VERSION, EIGEN_MAJOR_VERSION,
                EIGEN_MINOR_VERSION, Eigen::SimdInstructionSetsInUse());
    // Every library whose code produces results' bits (also in every results file: /@libraries).
    for (const auto& [name, version] : library_versions())
      if (name != "compiler" && name != "eigen")
        std::printf("%-10s %s\n", (name + ":").c_str(), version.c_str());
    // What results depend on besides their inputs, and this core's roof (both in every results
    // file a run writes).
    std::printf("cpu class: %s\n", cpu_class().c_str());
    std::printf("kernels:   %s (LIBXSMM_TARGET=hsw ONEDNN_MAX_CPU_ISA=AVX2 keep them at AVX2)\n",
                kernel_paths().c_str());
    std::printf(
        "bf16:      %s (precision = \"bf16\" products; SIRL_BF16=emulate forces the "
        "emulation)\n",
        bf16_backend());
    std::printf("fp32 roof: %.1f GFLOP/s per core (measured now)\n", fp32_roof_gflops_per_core());
    if (const double bf16 = bf16_roof_gflops_per_core(); bf16 > 0)
      std::printf("bf16 roof: %.1f GFLOP/s per core (measured now, the unit above)\n", bf16);
    return 0;
  };
}

}  // namespace sirl::app
