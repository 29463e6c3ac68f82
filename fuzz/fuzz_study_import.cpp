// libFuzzer target: any bytes as a study import file, CSV or JSON (the first byte chooses). A bad
// file must be one std::invalid_argument naming the line or record; any other exception, a crash,
// a stack overflow or a sanitizer report is a bug.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include "datasets/study.h"
#include "datasets/study_import.h"

namespace {

const sirl::Dataset& grid_study_data() {
  static const sirl::Dataset d = [] {
    sirl::Study s;
    s.env = "grid";
    return sirl::study_dataset(s);
  }();
  return d;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  // One file per process, rewritten each run (the importers read paths), removed at exit.
  static const struct Scratch {
    std::string path = (std::filesystem::temp_directory_path() /
                        ("sirl_fuzz_import_" + std::to_string(::getpid())))
                           .string();
    ~Scratch() {
      std::error_code ec;
      std::filesystem::remove(path, ec);
    }
  } scratch;
  const std::string& path = scratch.path;
  const bool json = data[0] & 1;
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data + 1), std::streamsize(size - 1));
  }
  sirl::Study s;
  s.env = "grid";
  try {
    json ? sirl::import_study_json(path, grid_study_data(), s)
         : sirl::import_study_csv(path, grid_study_data(), s);
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
