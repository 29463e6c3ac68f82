// "Did you mean …?" for a mistyped name (a command, a profile): the known name closest to it by
// edit distance (insertions, deletions, substitutions and swaps of neighbours), when it is close
// enough to be the likely intent.
#pragma once
#include <string>
#include <vector>

namespace sirl {

// Optimal-string-alignment distance between a and b, ASCII case-insensitive.
int edit_distance(const std::string& a, const std::string& b);

// The name in `known` closest to `typed`, if within max(1, |typed| / 3) edits (at most 2) and
// closer than every other name; "" otherwise (no guess is better than a wrong one).
std::string closest_name(const std::string& typed, const std::vector<std::string>& known);

// " (did you mean 'NAME'?)" for closest_name, or "".
std::string did_you_mean(const std::string& typed, const std::vector<std::string>& known);

}  // namespace sirl
