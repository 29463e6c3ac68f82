// libFuzzer target: any HDF5 bytes as a results file someone else wrote (a shard, an --against
// file, a file downloaded with a paper), behind a checksum frame recomputed over them: a crafted
// file passes the frame, as anyone's can. Reading it (`sirl export`, `merge`, `inspect`) must end
// in one H5Error; a crash, any other exception or a sanitizer report is a bug.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "results/durable.h"
#include "results/h5.h"
#include "results/results_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  namespace fs = std::filesystem;
  static const struct Scratch {
    fs::path dir = fs::temp_directory_path() / ("sirl_fuzz_results_" + std::to_string(::getpid()));
    Scratch() { fs::create_directories(dir); }
    ~Scratch() {
      std::error_code ec;
      fs::remove_all(dir, ec);
    }
  } scratch;
  const std::string body = (scratch.dir / "body").string(), file = (scratch.dir / "r.h5").string();
  {
    std::ofstream out(body, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  }
  // The frame the engine writes (results/results_file.cpp): magic, the body's XXH3-128, NULs.
  std::string head = "SIRLRESULTS2\nxxh3-128 " + sirl::file_digest(body) + "\n";
  head.resize(1024, '\0');
  {
    std::ofstream out(file, std::ios::binary | std::ios::trunc);
    out.write(head.data(), std::streamsize(head.size()));
    out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  }
  try {
    sirl::read_run_info(file);
    sirl::read_results_records(file);
  } catch (const sirl::H5Error&) {
  }
  return 0;
}
