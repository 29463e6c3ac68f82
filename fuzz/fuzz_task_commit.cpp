// libFuzzer target: any bytes as a committed task file (what a resumed run or an MPI rank reads
// from OUT.h5.tasks/). A bad file must be one H5Error naming the task; a crash inside the HDF5
// library, any other exception or a sanitizer report is a bug.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "kernels/rng.h"
#include "results/h5.h"
#include "results/task_store.h"

namespace {

// The task every input claims to be: the seed corpus holds a real commit of it.
constexpr const char* kKey = "grid/s0/sirl/N100/rep";

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  namespace fs = std::filesystem;
  // One directory per process, the input rewritten into it each run, removed at exit.
  static const struct Scratch {
    fs::path dir = fs::temp_directory_path() / ("sirl_fuzz_commit_" + std::to_string(::getpid()));
    Scratch() { fs::create_directories(dir); }
    ~Scratch() {
      std::error_code ec;
      fs::remove_all(dir, ec);
    }
  } scratch;
  const fs::path& dir = scratch.dir;
  char name[32];
  std::snprintf(name, sizeof name, "%016llx.h5",
                static_cast<unsigned long long>(sirl::seed_from_key(kKey, 0)));
  {
    std::ofstream out(dir / name, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  }
  try {
    sirl::TaskStore::load_from(dir, kKey);
  } catch (const sirl::H5Error&) {
  }
  return 0;
}
