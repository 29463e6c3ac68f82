// What each hyper-parameter sets, for the keys page (`sirl plan --keys`, docs/profile-keys.md).
// Declared beside the fields themselves (engine/hyperparams.cpp's one table of keys).
#pragma once
#include <string>
#include <vector>

#include "datasets/hyper_value.h"

namespace sirl {

// Every key with the engine's default (an environment may set its own: EnvSpec::hyper) and what
// it sets, in hyper_keys() order.
struct HyperKeyDoc {
  std::string key;
  HyperValue value;
  std::string doc;
};
std::vector<HyperKeyDoc> hyper_key_docs();

}  // namespace sirl
