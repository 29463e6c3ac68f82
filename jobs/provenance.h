// What a result's bits depend on besides its inputs: the compiler and the versions of the
// libraries whose code runs in the engine, as this build links them. Every results file records
// it (/@libraries) and `sirl version` prints it.
#pragma once
#include <string>
#include <utility>
#include <vector>

namespace sirl {

// {name, version} in a fixed order: compiler, eigen, libxsmm, onednn, cholmod, mujoco, hdf5,
// onetbb, xxhash.
std::vector<std::pair<std::string, std::string>> library_versions();
// The same as one line: "compiler GCC 12.2.0; eigen 3.4.0; …".
std::string library_versions_text();

}  // namespace sirl
