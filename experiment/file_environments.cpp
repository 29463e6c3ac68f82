#include "experiment/file_environments.h"

#include <memory>
#include <stdexcept>

#include "datasets/environments.h"
#include "datasets/exact_text.h"
#include "results/environment_file.h"

namespace sirl {

namespace {

// The data half of every task digest on this environment: the file's content (not its path: a
// copy elsewhere is the same environment), the group read and the streams drawn from.
std::string describe(const FileEnvironment& e, const std::string& group) {
  return "file xxh3=" + e.xxh3 + " group=" + group + " streams=" + e.streams + "\n";
}

}  // namespace

void declare_file_environment(const FileEnvironment& e) {
  const std::string group = e.group.empty() ? e.name : e.group;
  for (const EnvSpec& s : environments()) {
    if (s.name != e.name) continue;
    if (!s.from_file)
      throw std::invalid_argument("[environments." + e.name +
                                  "]: a built-in environment's name; choose another");
    if (s.describe_data(EnvConfig{}) != describe(e, group))
      throw std::invalid_argument("[environments." + e.name +
                                  "]: declared twice with different files, groups or streams");
    return;
  }
  if (!e.streams.empty()) env_spec(e.streams);  // throws naming the known environments
  auto data = std::make_shared<const Dataset>(
      read_environment_file(EnvironmentFileSpec{e.name, e.path, e.xxh3, group}));
  EnvSpec spec;
  spec.name = e.name;
  spec.title = e.title.empty() ? e.name : e.title;
  spec.description = e.description.empty() ? "read from " + e.path : e.description;
  spec.from_file = true;
  spec.beyond_paper = true;
  spec.streams = e.streams;
  spec.view = data->point_dim == 3 ? EnvView::arm : EnvView::path;
  // The study page draws a file's 2-D points as paths (its arm view is JacoRobot's table scene,
  // which a file's 3-D points in their own units would not fit).
  spec.in_study = data->point_dim == 2;
  spec.study_features = e.description.empty() ? "the features of " + spec.title : e.description;
  spec.make = [data](const EnvConfig&) { return *data; };
  spec.trajectories = [T = data->count](const EnvConfig&) { return T; };
  spec.input_dim = [D = data->input_dim](const EnvConfig&) { return D; };
  spec.describe_data = [text = describe(e, group)](const EnvConfig&) { return text; };
  spec.draw = draw_points;  // the file's points as they are; none: no path
  register_environment(std::move(spec));
}

}  // namespace sirl
