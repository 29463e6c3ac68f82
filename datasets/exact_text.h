// Numbers as text that round-trips: two values print alike only if they are the same double.
// The settings half of a task's digest is written with these, so a digest changes exactly when a
// value does.
#pragma once
#include <array>
#include <cstddef>
#include <cstdio>
#include <string>

namespace sirl {

inline std::string exact_number(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// "a,b,c": each element as exact_number.
template <typename T, size_t K>
std::string exact_list(const std::array<T, K>& a) {
  std::string s;
  for (size_t i = 0; i < K; ++i) {
    if (i) s.push_back(',');
    s.append(exact_number(double(a[i])));
  }
  return s;
}

}  // namespace sirl
