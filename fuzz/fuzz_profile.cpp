// libFuzzer target: any bytes as a profile. A malformed profile must be one ProfileError (its
// "file:line: what" message); any other exception, a crash or a sanitizer report is a bug.
#include <cstddef>
#include <cstdint>
#include <string>

#include "experiment/profile.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    sirl::parse_profile(std::string(reinterpret_cast<const char*>(data), size), "fuzz.toml");
  } catch (const sirl::ProfileError&) {
  }
  return 0;
}
