// Environments a profile declares from a file ([environments.<name>]: docs/environment-files.md),
// registered beside the built-in ones so every task kind, figure and report runs on them as on
// GridRobot. The file is read and checked once, when the profile is read: a bad file is one
// line before anything runs.
#pragma once
#include <string>

namespace sirl {

struct FileEnvironment {
  std::string name;         // the profile's name for it (1-32 of a-z, 0-9, _)
  std::string path;         // the environment file (resolved against the profile's folder)
  std::string xxh3;         // the file's XXH3-128, as the profile names it
  std::string group;        // /datasets/<group> in the file (default: name)
  std::string title;        // for figures (default: name)
  std::string description;  // one line (default: "read from <file>")
  std::string streams;      // the environment whose random streams it draws from (default: its own)
};

// Reads and checks the file (results/environment_file.h) and registers the environment. A name
// already registered with the same file content, group and streams is left as it is (a profile
// read twice in one process); a built-in name, or one declared with other content, throws
// std::invalid_argument, as does a bad file (one line naming it).
void declare_file_environment(const FileEnvironment& e);

}  // namespace sirl
