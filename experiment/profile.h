// A run profile (configs/*.toml): the experiment grid — environments × methods × N × M × seeds ×
// frozen × VAE pre-training — plus the query budgets, the teacher and hyper-parameter overrides.
// Parsed and fully validated before any work starts: every error names the file, the line and
// what was expected.
#pragma once
#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "datasets/environments.h"
#include "datasets/query_bundle.h"
#include "datasets/study.h"
#include "engine/active_queries.h"
#include "engine/hyperparams.h"
#include "engine/representation.h"

namespace sirl {

struct ProfileError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

// A method with its VAE pre-training switch and, for SIRL, how its triplets were chosen:
// "sirl", "sirl+vae", "multipref10+vae", "sirl@vote", "sirl+vae@infogain", …
struct Variant {
  Method method = Method::sirl;
  bool vae = false;
  Selection selection = Selection::uniform;  // "@vote", "@infogain": engine/active_queries.h
  std::string external;  // Method::external: its name, [external.<name>] (the variant's name)
  std::string name() const;
  bool operator==(const Variant&) const = default;
};
// Throws std::invalid_argument for unknown names, "+vae" on vae/random, or a selection on a
// method other than SIRL. External methods are not parsed from names: [external.<name>] declares
// them.
Variant parse_variant(const std::string& name);

struct TpaGrid {
  std::vector<Variant> methods;
  std::vector<int64_t> N, M;
  // Per variant: which of frozen (true) / unfrozen (false) to run. "best" in the file means the
  // paper's best configuration: SIRL (with or without VAE) frozen, every other method unfrozen.
  std::vector<bool> frozen;  // empty = "best"
};

// The numeric axes of the experiment grid for one environment (a profile may scale an expensive
// environment down: e.g. JacoRobot with fewer seeds or M points in `quick`).
struct EnvAxes {
  std::vector<int64_t> seeds, fpe_N, tpa_N, tpa_M, ablation_N, ablation_M;
  // Keep the networks' weights (`params`) in the results file. They always live in the task
  // files while the run goes on (resume needs them); off by default for JacoRobot, whose φ and
  // VAE hold 3.1 M and 6.3 M floats each.
  bool store_weights = true;
};

// [study]: the simulated cohort `sirl run` takes through the user-study pipeline (Fig. 6) as
// task kinds of the plan (experiment/study_tasks.h).
struct StudyPlan {
  bool enabled = false;
  CohortConfig cohort;  // env, trajectories, users, similarity, preference, beta, mistake
  int epochs = 3000, tpa_epochs = 1000, seeds = 5, splits = 50;
  bool random_frozen = false;  // random = "unfrozen" (default, the paper's best) or "frozen"
};

// One teacher of a noise axis: the main teacher ([teacher]'s scalars, or the paper's perfect
// oracle) with one key changed to a value listed in [teacher] (beta = [10, 1, 0] gives three).
struct TeacherPoint {
  std::string tag;            // "beta=1", "mistake=0.2", "attend=0.5": part of its cells' task keys
  std::string axis;           // "beta", "mistake" or "attend"
  double level = 0;           // the axis value
  QueryBundleConfig queries;  // the profile's [queries] answered by this teacher
};

// [robustness]: the cells every noisy teacher runs, beside the main grid's (Fig. "robustness"):
// FPE of each query-trained method at each N, TPA of every method at each N × M. The main
// teacher's cells of the same sizes are the axes' reference points (added to the main grid).
struct RobustnessGrid : TpaGrid {  // its cells' methods, N, M and frozen rule, as in [tpa]
  std::vector<TeacherPoint> teachers;
};

// [external.<name>]: a representation trained outside the engine, handed in as its embedding of
// Ξ per environment × seed × N (results/external_embeddings.h). It joins [fpe]'s and [tpa]'s
// methods under its own name; its TPA cells are frozen only (it has no weights to fine-tune).
struct ExternalMethod {
  std::string name;
  std::string embeddings;  // the file, absolute (a relative path is the profile file's folder's)
  std::string xxh3;  // the file's XXH3-128, as `xxh128sum` prints it: a changed file is refused
  std::string description;
  std::vector<std::string> envs;  // the environments it has embeddings for (default: all)
};

// One combination of an environment's hyper-parameter axes ([hyper.<env>] keys given as lists:
// "sirl.epochs" = [100, 300]): its tag ("sirl.epochs=300", axes joined by ";", in the order the
// profile gives them) and its values. The first combination (each axis's first value) is the
// base point: Profile::hyper holds it and its tasks carry no point (the keys and digests a
// profile without the axes gives them).
struct HyperPoint {
  std::string tag;
  Hyper hyper;
};

struct Profile {
  std::string path, text;  // where it came from, and its exact text (recorded in results)
  std::string name, description;
  std::vector<std::string> envs;
  std::vector<int64_t> seeds;
  QueryBundleConfig queries;
  std::vector<Variant> fpe_methods;
  std::vector<int64_t> fpe_N;
  TpaGrid tpa;
  // [tpa] stop = { <variant> = "<rule>", <env> = { <variant> = "<rule>" } }: the tpa.stop rule
  // ("fixed", "converged", "converged-unfrozen") of every TPA cell of that variant — [tpa]'s,
  // [ablation]'s and [robustness]'s — over [hyper]'s, e.g. the paper's epochs for the one method
  // where a stopping rule was not equivalent (configs/jaco-fig5.toml). A rule is a property of the
  // method, not of the grid a cell is listed in, so a cell two grids share is one task. An
  // environment's entry wins over the one for every environment (the rules were tested per
  // environment). Keys: tpa_stop_key(env or "", variant name).
  std::map<std::string, std::string> tpa_stop_by_method;
  // [pref] stop = { <variant> = "<rule>", <env> = { <variant> = "<rule>" } }: the pref.stop rule
  // ("fixed", "converged") a preference-trained variant's φ trains by, over [hyper]'s, in every
  // environment or in the one named (its entry wins). A rule tested equivalent for one method is
  // applied to that method alone (docs/stopping-rule.md). Keys: tpa_stop_key(env or "", variant).
  std::map<std::string, std::string> pref_stop_by_method;
  // [tpa] protocols: how [tpa]'s cells score a representation: "paper" (the paper's reward head,
  // engine/tpa.h) and "linear" (linear evaluation: a Bradley–Terry linear head fit to convergence,
  // engine/linear_tpa.h). Default: both. [ablation] and [robustness] cells are the paper's.
  std::vector<std::string> tpa_protocols{"paper", "linear"};
  bool runs_protocol(const std::string& protocol) const;
  // Top-level `references = false` leaves the references truth and raw out (default: in every
  // FPE and TPA table; docs/linear-evaluation.md).
  bool references = true;
  // Top-level `budget_minutes`: the wall time the profile is meant to fit on the machine its
  // comment names (0: none). `sirl reproduce` predicts this machine's time first and says when it
  // is well over.
  double budget_minutes = 0;
  // Fig. 7: every listed method × {frozen, unfrozen} × {no VAE, VAE} (where VAE applies).
  std::vector<Method> ablation_methods;
  std::vector<int64_t> ablation_N, ablation_M;
  std::map<std::string, Hyper> hyper;  // per env: the paper's values with this profile's overrides
  // Per env with hyper-parameter axes: every combination, the base point first (absent: none).
  std::map<std::string, std::vector<HyperPoint>> hyper_points;
  // Top-level `precision` ("fp32" or "bf16"): every network of the run, the study's included;
  // [hyper.<env>] precision may still set one environment apart.
  std::string precision = "fp32";
  EnvConfig data;  // Ξ's settings ([jaco]: trajectories, data_seed, max_deformation)
  // Per env: the top-level seeds/N/M unless the env's own table ([grid], [jaco], …) overrides them.
  std::map<std::string, EnvAxes> axes;
  StudyPlan study;
  RobustnessGrid robustness;
  // [active]: how the active variants choose their triplets, per environment ([active.<env>]
  // overrides [active]; every env has one).
  std::map<std::string, ActiveRounds> active;
  std::vector<ExternalMethod> external;
};

// The hyper-parameter points a planner expands environment `env`'s cells over: "" (the base
// point) first, then the tags of the other combinations of its axes.
std::vector<std::string> hyper_point_tags(const Profile& p, const std::string& env);
// RunInfo::hyper_points for the profile: "<env>\t<base tag>\t<tag>…" per environment with axes.
std::string hyper_points_text(const Profile& p);
// The values of point `tag` of environment `env` ("" = the base point, Profile::hyper). Throws
// std::invalid_argument for an unknown tag.
const Hyper& hyper_at(const Profile& p, const std::string& env, const std::string& tag);
// The key of Profile::tpa_stop_by_method for one variant in one environment ("" = every one).
std::string tpa_stop_key(const std::string& env, const std::string& variant);
// What a TPA cell of variant v trains its heads with: hyper_at's values with the variant's
// [tpa] stop rule, if the profile gives it one.
Hyper tpa_cell_hyper(const Profile& p, const std::string& env, const std::string& tag,
                     const Variant& v);

// What a representation of variant v trains with: hyper_at's values with the variant's [pref]
// stop rule, if the profile gives it one.
Hyper rep_task_hyper(const Profile& p, const std::string& env, const std::string& tag,
                     const Variant& v);

// Whether variant v has cells in environment env: every method has, but an external method only
// in the environments its [external.<name>] lists.
bool runs_in(const Profile& p, const Variant& v, const std::string& env);
// The [external.<name>] of profile p; throws std::invalid_argument for an unknown name.
const ExternalMethod& external_method(const Profile& p, const std::string& name);
// Whether `name` may name an external method: [a-z][a-z0-9_-]{0,39}, not a built-in method's.
// Returns "" if so, else why not.
std::string external_name_problem(const std::string& name);

// The queries a cell's teacher answers: the profile's own for "" (the main teacher), else those
// of the robustness teacher with that tag. Throws std::invalid_argument for an unknown tag.
const QueryBundleConfig& queries_for(const Profile& p, const std::string& teacher);

Profile parse_profile(const std::string& text, const std::string& path = "<profile>");

// Whether any network of the run has bf16 products: an environment's [hyper] precision, or the
// top-level one (the user study's).
bool runs_bf16(const Profile& p);
// The precision the networks of environment `env` run in (the top-level one for an environment
// the profile has no [hyper] entry for, such as the study's tasks).
const std::string& precision_of(const Profile& p, const std::string& env);
// Reads the file; a bare name ("quick") resolves to configs/<name>.toml in the working directory
// or among the installed profiles. `extends = "quick"` (or a list) in a file makes it its parents'
// tables with its own keys on top (tables merge key by key; arrays and values replace), a parent
// named relative to the file's folder first; each of `settings` ("KEY=VALUE", VALUE in TOML, KEY
// dotted: hyper.grid."sirl.epochs"=100, seeds=[0,1]) goes on top of that, in order. A composed
// profile's text (what results files record) is the resolved TOML. Errors name the file and line
// that set the bad value (or "--set KEY=VALUE"). Throws ProfileError.
Profile load_profile(const std::string& path_or_name,
                     const std::vector<std::string>& settings = {});

// The keys of the sections declared as data (experiment/profile_settings.h: [queries], [active],
// [study]) as Markdown tables: type, accepted values, default, what each sets (`sirl plan --keys`;
// docs/profile-keys.md).
std::string profile_keys_markdown();

// The names of the profiles shipped in configs/ ("beyond, jaco-fig5, paper, …"), for --help.
std::string bundled_profile_names();
// The same names as a list (empty when there is no data folder).
std::vector<std::string> bundled_profiles();

// The frozen settings a TPA cell of this variant runs with under `grid`.
std::vector<bool> frozen_settings(const TpaGrid& grid, const Variant& v);
// The paper's best mode of a method's TPA cells (Fig. 5): SIRL, with or without VAE pre-training
// and whatever its query selection, frozen; every other method unfrozen, but an external method,
// which has frozen cells only.
bool is_best_mode(const Variant& v, bool frozen);

}  // namespace sirl
