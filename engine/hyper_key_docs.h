// What each hyper-parameter sets, for the keys page (`sirl plan --keys`, docs/profile-keys.md).
// Declared beside the fields themselves (engine/hyperparams.cpp's one table of keys).
#pragma once
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "datasets/hyper_value.h"

namespace sirl {

// What a key accepts, declared beside it: a number (an integer key's too, and each width of a
// widths key) in [lo, hi], either end open, or, for a word key, one of its words. validate()
// refuses anything else, naming the key and this.
struct HyperAccept {
  double lo = -INFINITY, hi = INFINITY;
  bool lo_open = false, hi_open = false;
  std::vector<std::pair<std::string, std::string>> words;  // (word, what it means), word keys
};
bool accepts(const HyperAccept& a, double x);
// ">= 1", "in (0, 1]", ...: the numeric range as the messages and the keys page write it.
std::string range_text(const HyperAccept& a);
// `"sum" (what it means) or "mean" (...)`: a word key's words as a message lists them.
std::string words_text(const HyperAccept& a);

// Every key with the engine's default (an environment may set its own: EnvSpec::hyper), what it
// sets and what it accepts, in hyper_keys() order.
struct HyperKeyDoc {
  std::string key;
  HyperValue value;
  std::string doc;
  HyperAccept accept;
};
std::vector<HyperKeyDoc> hyper_key_docs();

}  // namespace sirl
