// Named random streams of one seed. Every stream the dataset/query code draws from is opened
// through one StreamSet, which refuses to open a name twice: two things that drew from one
// stream would be correlated (e.g. a human's reward weights and the first queries it answers).
#pragma once
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "kernels/rng.h"

namespace sirl {

class StreamSet {
 public:
  explicit StreamSet(uint64_t seed) : seed_(seed) {}
  // The stream seed_from_key(name, seed). Throws std::logic_error if `name` was opened before.
  Rng open(const std::string& name) {
    for (const auto& n : opened_)
      if (n == name) throw std::logic_error("random stream '" + name + "' opened twice");
    opened_.push_back(name);
    return Rng(seed_from_key(name, seed_));
  }
  const std::vector<std::string>& opened() const { return opened_; }

 private:
  uint64_t seed_;
  std::vector<std::string> opened_;
};

}  // namespace sirl
