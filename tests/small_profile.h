// A small GridRobot profile shared by the profile, plan, estimate and scheduler tests: three
// seeds, the FPE and TPA grids and an ablation, with two hyper-parameter overrides.
#pragma once

namespace sirl::test {

inline constexpr const char* kSmallProfile = R"(
name = "t"
envs = ["grid"]
seeds = [0, 1, 2]
[queries]
similarity = 300
preference = 300
tpa_pairs = 100
[fpe]
methods = ["sirl", "sirl+vae", "vae", "random"]
N = [100, 200, 300]
[tpa]
methods = ["sirl", "multipref10", "random"]
N = [100, 300]
M = [10, 80]
[ablation]
methods = ["sirl", "random"]
N = [300]
M = [80]
[hyper.grid]
"sirl.epochs" = 7
"tpa.hidden" = [32, 16]
)";

}  // namespace sirl::test
