// The message of the ProfileError that parsing `text` throws ("no error" when it parses), for
// the tests of the profile's refusals.
#pragma once
#include <string>

#include "experiment/profile.h"

namespace sirl::test {

inline std::string profile_error_of(const std::string& text) {
  try {
    parse_profile(text, "bad.toml");
  } catch (const ProfileError& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace sirl::test
