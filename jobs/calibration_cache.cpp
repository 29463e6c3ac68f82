#include "jobs/calibration_cache.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "probes/cpu_class.h"
#include "results/durable.h"

namespace sirl {

namespace {

constexpr const char* kFormat = "sirl-calibration-1";

std::string folder() {
  const char* dir = std::getenv("SIRL_CALIBRATION_CACHE");
  return dir && *dir ? dir : "";
}

// This binary, by its bytes: any rebuild is another engine and calibrates afresh.
const std::string& binary_digest() {
  static const std::string digest = [] {
    try {
      return file_digest("/proc/self/exe");
    } catch (const std::exception&) {
      return std::string();  // unreadable: nothing is reused
    }
  }();
  return digest;
}

// The file holding `what`'s calibration: "<XXH3-128 of class, binary and what>.cal".
std::string path_of(const std::string& dir, const std::string& what) {
  const std::string key = cpu_class() + "\n" + binary_digest() + "\n" + what;
  return (std::filesystem::path(dir) / (bytes_digest(key.data(), key.size()) + ".cal")).string();
}

}  // namespace

std::optional<std::vector<double>> load_calibration(const std::string& what) {
  const std::string dir = folder();
  if (dir.empty() || binary_digest().empty()) return std::nullopt;
  const std::string path = path_of(dir, what);
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec) || std::filesystem::file_size(path, ec) > 65536)
    return std::nullopt;  // none, a FIFO or anything else than what save_calibration writes
  std::ifstream in(path);
  std::string format;
  if (!std::getline(in, format) || format != kFormat) return std::nullopt;
  std::vector<double> values;
  std::string word;
  while (in >> word) {
    char* end = nullptr;
    const double v = std::strtod(word.c_str(), &end);
    if (end == word.c_str() || *end != '\0' || !std::isfinite(v) || v < 0) return std::nullopt;
    values.push_back(v);
  }
  if (values.empty()) return std::nullopt;
  return values;
}

void save_calibration(const std::string& what, const std::vector<double>& values) {
  const std::string dir = folder();
  if (dir.empty() || binary_digest().empty()) return;
  std::ostringstream text;
  text << kFormat << "\n";
  char buf[40];
  for (double v : values) {
    std::snprintf(buf, sizeof buf, "%.17g\n", v);  // round-trips exactly
    text << buf;
  }
  try {
    std::filesystem::create_directories(dir);
    write_text_atomically(path_of(dir, what), text.str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "sirl: warning: SIRL_CALIBRATION_CACHE: %s (calibrations not kept)\n",
                 e.what());
  }
}

}  // namespace sirl
