#include "experiment/install_paths.h"

#include <cstdlib>
#include <stdexcept>
#include <system_error>

namespace sirl {

namespace fs = std::filesystem;

namespace {

bool holds_configs(const fs::path& dir) {
  std::error_code ec;
  return !dir.empty() && fs::is_directory(dir / "configs", ec);
}

}  // namespace

fs::path data_dir() {
  if (const char* env = std::getenv("SIRL_DATA_DIR"); env && *env) {
    if (!holds_configs(env))
      throw std::runtime_error(std::string("SIRL_DATA_DIR=") + env + " holds no configs/ folder");
    return env;
  }
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const fs::path share = exe.parent_path().parent_path() / "share" / "sirl-bench";
    if (holds_configs(share)) return share;
  }
  if (const char* only = std::getenv("SIRL_INSTALLED_ONLY"); !(only && *only))
    if (holds_configs(SIRL_SOURCE_DIR)) return SIRL_SOURCE_DIR;
  throw std::runtime_error(
      "cannot find sirl-bench's data folder (configs/, results/, python/): "
      "not beside the binary (" +
      exe.string() + " → ../share/sirl-bench); set SIRL_DATA_DIR");
}

std::string python_interpreter() {
  if (const char* env = std::getenv("SIRL_PYTHON"); env && *env) return env;
  return SIRL_PYTHON;
}

}  // namespace sirl
