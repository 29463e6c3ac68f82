#include "jobs/provenance.h"

#include "datasets/jaco_robot.h"
#include "jobs/scheduler.h"
#include "kernels/gemm.h"
#include "kernels/onednn_matmul.h"
#include "kernels/sparse_cholesky.h"
#include "results/durable.h"
#include "results/h5.h"

namespace sirl {

namespace {

std::string compiler() {
#if defined(__clang__)
  return std::string("clang ") + __clang_version__;
#elif defined(__GNUC__)
  return std::string("GCC ") + __VERSION__;
#else
  return "unknown";
#endif
}

}  // namespace

std::vector<std::pair<std::string, std::string>> library_versions() {
  return {
      {"compiler", compiler()},     {"eigen", eigen_version()},     {"libxsmm", libxsmm_version()},
      {"onednn", onednn_version()}, {"cholmod", cholmod_version()}, {"mujoco", mujoco_version()},
      {"hdf5", hdf5_version()},     {"onetbb", tbb_version()},      {"xxhash", xxhash_version()}};
}

std::string library_versions_text() {
  std::string s;
  for (const auto& [name, version] : library_versions())
    s += (s.empty() ? "" : "; ") + name + " " + version;
  return s;
}

}  // namespace sirl
