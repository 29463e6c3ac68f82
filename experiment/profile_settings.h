// The profile's scalar sections declared once, as data: each key with its field, its accepted
// range and one line saying what it sets. From these declarations come the parsing (unknown keys,
// types and ranges refused with file:line: experiment/profile.cpp), the digest's text of a
// section (experiment/task_settings.cpp), and the reference table `sirl plan --keys` prints
// (profile_keys_markdown in experiment/profile.h; docs/profile-keys.md is that output). A field's
// default is its struct's initial value, so it is written once too. A new setting of these sections
// is one line here plus its use.
//
// A section's declaration is a visitor: kActiveSettings(a, f) calls f(info, field) for each key in
// order (a may be const).
#pragma once
#include <array>
#include <limits>
#include <string>
#include <type_traits>

#include "datasets/exact_text.h"

namespace sirl {

inline constexpr double kInfinity = std::numeric_limits<double>::infinity();

struct SettingInfo {
  const char* key;
  double lo = 0, hi = 0;  // integers and numbers: the values accepted
  const char* doc = "";   // what it sets, one line
  // A true/false field set by one of two words ({false's, true's}); empty for other fields (a
  // bool without words is a TOML true/false).
  std::array<const char*, 2> words{};
  // [teacher]: a list of values, instead of one, makes a noise axis (one teacher per value).
  bool axis = false;
  // The default as the reference page states it, where it is not the struct's value (an
  // environment's lists default to the profile's).
  const char* default_text = nullptr;
  bool required = false;  // the table must give it (a list: not empty)
};

// [queries]: each seed's query budgets.
inline constexpr auto kQueriesSettings = [](auto& q, auto&& f) {
  f(SettingInfo{"similarity", 1, 1e7, "similarity triplets answered per seed (the largest N)"},
    q.similarity);
  f(SettingInfo{"preference", 1, 1e7,
                "preference pairs per seed for each of SinglePref, MultiPref-10 and -50"},
    q.preference);
  f(SettingInfo{"tpa_pairs", 2, 1e7,
                "labelled pairs per test reward (80 % train: M up to 0.8 tpa_pairs)"},
    q.tpa_pairs);
  f(SettingInfo{"fpe_trajectories", 2, 1e7,
                "labelled trajectories for FPE's probe (clamped to the trajectory count)"},
    q.fpe_trajectories);
};

// [active] and [active.<env>]: how an active variant's ensemble asks, round by round.
inline constexpr auto kActiveSettings = [](auto& a, auto&& f) {
  f(SettingInfo{"members", 2, 64, "K: the ensemble's members"}, a.members);
  f(SettingInfo{"pool", 1, 1e7, "candidate triplets drawn per round (at least batch)"}, a.pool);
  f(SettingInfo{"batch", 1, 1e7, "triplets asked per round"}, a.batch);
  f(SettingInfo{"round_epochs", 1, 1e6, "epochs each member trains per round (warm start)"},
    a.round_epochs);
  f(SettingInfo{"mu", 1e-9, 1e9, "crowd-kernel μ, in units of a member's median pair distance"},
    a.mu);
};

// [study]: the simulated cohort of the user-study pipeline and its analysis.
inline constexpr auto kStudySettings = [](auto& s, auto&& f) {
  f(SettingInfo{"env", 0, 0, "the cohort's environment (2-D points: jaco2, grid or a file's)"},
    s.cohort.env);
  f(SettingInfo{"trajectories", 10, 1e6, "the trajectory space's size"}, s.cohort.trajectories);
  f(SettingInfo{"users", 2, 1e4, "simulated participants"}, s.cohort.users);
  f(SettingInfo{"similarity", 1, 1e5, "similarity queries each participant answers"},
    s.cohort.similarity);
  f(SettingInfo{"preference", 4, 1e5, "preference queries each participant answers"},
    s.cohort.preference);
  f(SettingInfo{"beta", 1e-9, kInfinity, "the simulated participants' Boltzmann rationality β"},
    s.cohort.beta);
  f(SettingInfo{"mistake", 0, 1, "probability a participant flips an answer"}, s.cohort.mistake);
  f(SettingInfo{"epochs", 1, 1e6, "SIRL's epochs on the pooled answers"}, s.epochs);
  f(SettingInfo{"tpa_epochs", 1, 1e6, "reward heads' epochs"}, s.tpa_epochs);
  f(SettingInfo{"seeds", 2, 100, "training seeds for FPE"}, s.seeds);
  f(SettingInfo{"splits", 1, 1000, "70/30 splits of each participant's preferences"}, s.splits);
  f(SettingInfo{"random",
                0,
                0,
                "the mode Random is evaluated in (the paper's best: unfrozen)",
                {"unfrozen", "frozen"}},
    s.random_frozen);
};

// [teacher]: the main simulated human (datasets/simulated_human.h); a list for an axis key keeps
// the main teacher's value of that key and makes each listed value one noisy teacher, whose
// cells [robustness] names.
inline constexpr auto kTeacherSettings = [](auto& q, auto&& f) {
  f(SettingInfo{"beta",
                0,
                kInfinity,
                "Boltzmann rationality β (\"inf\": the perfect oracle); a list: a noise axis",
                {},
                true},
    q.teacher.beta);
  f(
      SettingInfo{
          "mistake", 0, 1, "probability of flipping an answer; a list: a noise axis", {}, true},
      q.teacher.mistake);
  f(SettingInfo{"skip", 0, kInfinity,
                "an answer is withheld when its options differ by less than this"},
    q.teacher.skip);
  f(SettingInfo{"equal", 0, kInfinity,
                "near-ties within this are answered as ties (preference 0.5, a coin flip)"},
    q.teacher.equal);
  f(SettingInfo{"attend",
                1e-9,
                1,
                "share of the features the teacher perceives (a per-seed subset); a list: a noise "
                "axis",
                {},
                true},
    q.attend);
};

// [<env>] ([grid], [jaco], a file environment's name): the grid's lists for that environment
// alone (an empty list: no such cell there) and whether its weights are kept. The table that holds
// an environment's data also takes the keys the environment reads itself (EnvSpec::data_keys).
inline constexpr auto kEnvTableSettings = [](auto& g, auto&& f) {
  f(SettingInfo{"seeds", 0, 1e9, "the seeds it runs (not empty)", {}, false, "the profile's seeds"},
    g.seeds);
  f(SettingInfo{"fpe_N", 1, 1e7, "FPE's N", {}, false, "[fpe] N"}, g.fpe_N);
  f(SettingInfo{"tpa_N", 1, 1e7, "TPA's N", {}, false, "[tpa] N"}, g.tpa_N);
  f(SettingInfo{"tpa_M", 1, 1e7, "TPA's M", {}, false, "[tpa] M"}, g.tpa_M);
  f(SettingInfo{"ablation_N", 1, 1e7, "the ablation's N", {}, false, "[ablation] N"}, g.ablation_N);
  f(SettingInfo{"ablation_M", 1, 1e7, "the ablation's M", {}, false, "[ablation] M"}, g.ablation_M);
  f(SettingInfo{"store_weights",
                0,
                0,
                "keep the networks' weights in the results file",
                {},
                false,
                "true; false for sampled environments (JacoRobot's 3.1 M-float φ)"},
    g.store_weights);
};

// The top level: what the profile is and what it runs on (the tables are read by their own
// declarations). `extends` is resolved before (load_profile).
inline constexpr auto kProfileSettings = [](auto& p, auto&& f) {
  f(SettingInfo{.key = "name", .doc = "the profile's name (results, reports)", .required = true},
    p.name);
  f(SettingInfo{.key = "description", .doc = "a few lines heading `sirl plan` and the report"},
    p.description);
  f(SettingInfo{.key = "envs",
                .doc = "the environments it runs (grid, grid2, jaco, jaco2, "
                       "driver, or a file's: [environments.<name>])",
                .required = true},
    p.envs);
  f(SettingInfo{.key = "seeds",
                .lo = 0,
                .hi = 1e9,
                .doc = "the seeds every environment runs",
                .required = true},
    p.seeds);
  f(SettingInfo{.key = "budget_minutes",
                .lo = 0,
                .hi = 1e8,
                .doc = "the wall time it is meant to fit (0: none); `sirl reproduce` warns when "
                       "this machine's prediction is well over"},
    p.budget_minutes);
  f(SettingInfo{.key = "precision",
                .doc = "\"fp32\" (the paper's) or \"bf16\" matrix products (fp32 accumulation)"},
    p.precision);
  f(SettingInfo{.key = "references",
                .doc = "score the references truth and raw beside the methods"},
    p.references);
};

// The grid: which cells run. A table's presence runs its part of the grid; [tpa] also takes
// `stop` and `protocols` (below), [robustness] is read as [tpa]'s cells for the noisy teachers.
// Methods are variant names (`sirl`, `sirl+vae`, `sirl@vote`, …: docs/methods.md); [ablation]
// takes method names and runs each with and without VAE pre-training, frozen and unfrozen.
inline constexpr auto kFpeSettings = [](auto& p, auto&& f) {
  f(SettingInfo{.key = "methods", .doc = "the methods whose FPE is measured", .required = true},
    p.fpe_methods);
  f(SettingInfo{.key = "N",
                .lo = 1,
                .hi = 1e7,
                .doc = "similarity triplets each φ learns from",
                .required = true},
    p.fpe_N);
};
inline constexpr auto kTpaSettings = [](auto& g, auto&& f) {
  f(SettingInfo{.key = "methods", .doc = "the methods whose TPA is measured", .required = true},
    g.methods);
  f(
      SettingInfo{
          .key = "N", .lo = 1, .hi = 1e7, .doc = "triplets each φ learns from", .required = true},
      g.N);
  f(SettingInfo{.key = "M",
                .lo = 1,
                .hi = 1e7,
                .doc = "labelled pairs each reward head learns from",
                .required = true},
    g.M);
  f(SettingInfo{.key = "frozen",
                .doc = "\"best\" (the paper's: SIRL frozen, the others unfrozen) or a list of "
                       "booleans (each mode listed runs for every method)",
                .default_text = "`\"best\"`"},
    g.frozen);
};
inline constexpr auto kAblationSettings = [](auto& p, auto&& f) {
  f(SettingInfo{.key = "methods",
                .doc = "methods (not variants), each run with and without VAE pre-training, "
                       "frozen and unfrozen",
                .required = true},
    p.ablation_methods);
  f(
      SettingInfo{
          .key = "N", .lo = 1, .hi = 1e7, .doc = "triplets each φ learns from", .required = true},
      p.ablation_N);
  f(SettingInfo{.key = "M",
                .lo = 1,
                .hi = 1e7,
                .doc = "labelled pairs each reward head learns from",
                .required = true},
    p.ablation_M);
};

// [external.<name>]: a representation trained elsewhere, read from its embeddings file (it joins
// [fpe] and [tpa], frozen; external-methods.md). Paths are the profile file's folder's.
inline constexpr auto kExternalSettings = [](auto& m, auto&& f) {
  f(SettingInfo{.key = "embeddings",
                .doc = "its embeddings file (`sirl evaluate` checks one)",
                .required = true},
    m.embeddings);
  f(SettingInfo{.key = "xxh3",
                .doc = "the file's XXH3-128, 32 lowercase hex digits (`xxh128sum FILE`): a "
                       "changed file is refused",
                .required = true},
    m.xxh3);
  f(SettingInfo{.key = "description", .doc = "one line for the report"}, m.description);
  f(SettingInfo{.key = "envs",
                .doc = "the environments it has embeddings for",
                .default_text = "the profile's envs"},
    m.envs);
};

// [environments.<name>]: an environment read from a file (environment-files.md), registered
// before `envs` and the environments' own tables are read.
inline constexpr auto kFileEnvironmentSettings = [](auto& e, auto&& f) {
  f(SettingInfo{.key = "file", .doc = "the environment file", .required = true}, e.path);
  f(SettingInfo{.key = "xxh3",
                .doc = "the file's XXH3-128, 32 lowercase hex digits (`xxh128sum FILE`)",
                .required = true},
    e.xxh3);
  f(SettingInfo{.key = "dataset",
                .doc = "its group /datasets/<dataset> in the file (≤ 256 characters)",
                .default_text = "the name"},
    e.group);
  f(SettingInfo{.key = "title",
                .doc = "its title in figures (≤ 64 characters)",
                .default_text = "the name"},
    e.title);
  f(SettingInfo{.key = "description",
                .doc = "one line (≤ 400 characters)",
                .default_text = "read from <file>"},
    e.description);
  f(SettingInfo{.key = "streams",
                .doc = "the environment whose random streams it draws from",
                .default_text = "its own"},
    e.streams);
};

// [tpa] protocols: the ways a TPA cell reads out a reward from φ, each listed at most once.
struct ProtocolInfo {
  const char* name;
  const char* doc;
};
inline constexpr std::array<ProtocolInfo, 2> kTpaProtocols = {{
    {"paper", "the paper's reward head on φ, trained by Adam (engine/tpa.h)"},
    {"linear", "linear evaluation: a Bradley–Terry linear head fit to convergence"},
}};

// " key=value" for each key `visit` declares, in order, values as exact text (a word field by
// its word): a section's part of a task digest's text (experiment/task_settings.cpp).
template <class S, class Visit>
std::string settings_text(const S& s, Visit visit) {
  std::string out;
  visit(s, [&](const SettingInfo& k, const auto& field) {
    using T = std::decay_t<decltype(field)>;
    out += std::string(" ") + k.key + "=";
    if constexpr (std::is_same_v<T, std::string>)
      out += field;
    else if constexpr (std::is_same_v<T, bool>)
      out += k.words[0] ? k.words[field ? 1 : 0] : (field ? "1" : "0");
    else
      out += exact_number(field);
  });
  return out;
}

}  // namespace sirl
