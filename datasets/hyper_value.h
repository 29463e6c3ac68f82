// A hyper-parameter value, typed as a profile's TOML gives it: an integer (epochs, batch), a
// number (rates, weights), a boolean, a word (precision, tpa.stop) or a list of widths.
// engine/hyperparams.h assigns it to its field, refusing a value of the wrong kind; an
// environment's registration (datasets/environments.h) lists its defaults in it.
#pragma once
#include <cstdint>
#include <string>
#include <variant>
#include <vector>

namespace sirl {

using HyperValue = std::variant<int64_t, double, bool, std::string, std::vector<int>>;

}  // namespace sirl
