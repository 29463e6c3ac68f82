// The environments, declared once each: name, what it is, how to build its Ξ, its sizes, the
// paper's hyper-parameters for it, how to draw one of its trajectories and what role it plays in
// the report. Code that needs an environment looks it up here; nothing outside this registry
// compares environment names. Adding an environment is one `register_environment` call
// (docs/ARCHITECTURE.md, "Adding an environment").
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "datasets/dataset.h"
#include "datasets/driver.h"
#include "datasets/grid_robot.h"
#include "datasets/hyper_value.h"
#include "datasets/jaco_robot.h"

namespace sirl {

// What a profile or the command line may set about Ξ; each environment reads its own part.
struct EnvConfig {
  GridConfig grid;
  JacoConfig jaco;      // trajectories, data seed, deformation size, object positions
  DriverConfig driver;  // trajectories, data seed
};

// One trajectory as a figure or the study page draws it: a path of points (2-D cell coordinates
// for a plane view, 3-D end-effector positions in metres for an arm view) and, for a plane view,
// the end angle in degrees.
struct TrajectoryView {
  std::vector<std::array<float, 3>> points;
  float end_angle_deg = 0;
  // An arm's pose at each waypoint: its base then every link frame, world positions (m), as the
  // compiled MJCF's forward kinematics placed them (empty for environments without an arm).
  std::vector<std::vector<std::array<float, 3>>> links;
};

// How a figure or the study page draws a trajectory: `plane`, GridRobot's cells and end angle;
// `arm`, an arm's 3-D path and poses; `path`, a path of 2-D points in the environment's own
// units, drawn to fit (Driver, a file's 2-D points).
enum class EnvView { plane, arm, path };
// "plane", "arm" or "path" (the results file's /datasets/<env>@view, the study page's view).
const char* view_name(EnvView v);

// A hyper-parameter default that differs from the engine's (GridRobot's) values, as the profile
// key and value `[hyper.<env>]` takes.
struct HyperDefault {
  std::string key;
  HyperValue value;
};

// An environment's profile table (its data_table, e.g. [jaco]) as the profile reader hands it
// over: each read takes the key's default when it is absent and refuses, naming the file and
// line, a value of the wrong type or outside [lo, hi].
struct DataTableReader {
  virtual ~DataTableReader() = default;
  virtual int64_t integer(const char* key, int64_t def, int64_t lo, int64_t hi) const = 0;
  virtual double number(const char* key, double def, double lo, double hi) const = 0;
};

struct EnvSpec {
  std::string name;         // the profile's and the results file's name: "grid", "jaco2", …
  std::string title;        // for figures: "GridRobot", …
  std::string description;  // one line for `--help` and the docs
  // Ξ is sampled (set_sample says how many trajectories, from which seed) rather than enumerated.
  // Sampled environments keep their network weights out of the results file by default (3.1 M
  // floats).
  bool sampled = false;
  // The profile table whose keys set Ξ (empty: Ξ is fixed). Both JacoRobot variants read [jaco].
  std::string data_table;
  // The environment that owns that table (data_table == name) says which keys it holds beside a
  // grid's axes (seeds, fpe_N, …) and reads them into an EnvConfig; null: its Ξ has no settings.
  std::vector<std::string> data_keys;
  void (*read_data)(const DataTableReader& table, EnvConfig& cfg) = nullptr;
  std::vector<HyperDefault> hyper;
  EnvView view = EnvView::plane;
  // Roles in the report and figures (stored as attributes of /datasets/<env>):
  bool in_claims = true;        // its cells decide the paper's claims H1/H2
  int fig3_rank = 0;            // > 0: Fig. 3 may be drawn on it; the highest rank present wins
  bool vae_weak_claim = false;  // the paper's "VAE severely underperforms" is checked on it
  bool in_study = false;        // the user study may run on it
  std::string study_features;   // the study page's one-line gloss of its features
  // Functions rather than plain pointers: an environment read from a file (experiment/
  // file_environments.h) carries its data with it.
  std::function<Dataset(const EnvConfig& cfg)> make;
  std::function<int64_t(const EnvConfig& cfg)> trajectories;  // |Ξ| without building it
  std::function<int(const EnvConfig& cfg)> input_dim;         // floats per trajectory
  // Ξ's settings as canonical text (datasets/exact_text.h): the data half of a task's digest, so
  // every field Ξ depends on must be in it. Empty: Ξ has no settings.
  std::function<std::string(const EnvConfig& cfg)> describe_data;
  // A sampled Ξ's size and data seed set in cfg (the user study's Ξ, or the small Ξ `sirl plan`
  // calibrates on); empty for an enumerated Ξ.
  std::function<void(EnvConfig& cfg, int64_t trajectories, uint64_t data_seed)> set_sample;
  std::function<TrajectoryView(const Dataset& d, int64_t row)> draw;
  // The name its random streams are keyed by (queries, initialisations: task_seed); empty: its
  // own name. An environment read from a file exported from a built-in one names that one, so
  // the two give the same cells.
  std::string streams;
  // Read from a file a profile declared ([environments.<name>]), not built into the engine.
  bool from_file = false;
  // Not one of the paper's environments (a file's, or one from other work): the paper made no
  // statement about it, so the report marks the claims decided on it "beyond the paper".
  bool beyond_paper = false;
  const std::string& stream_name() const { return streams.empty() ? name : streams; }
};

// One trajectory's Dataset::points as a view (2-D points on the plane, 3-D ones in space).
TrajectoryView draw_points(const Dataset& d, int64_t row);

// Every registered environment, in registration order (the built-in five first).
const std::vector<EnvSpec>& environments();
// Throws std::invalid_argument naming the known environments.
const EnvSpec& env_spec(const std::string& name);
// "grid, grid2, jaco, jaco2, driver".
std::string env_names();
// Adds an environment (an extension, or a test's toy environment). Throws std::invalid_argument
// for a taken or malformed name or a missing function. Not thread-safe: register before running.
void register_environment(EnvSpec spec);

}  // namespace sirl
