// One mechanism for an enum's names: a table of {value, name} pairs, read both ways. Every enum
// whose values have names (a query selection, a method's role, a shard's phase, a setting's type)
// declares such a table once beside it, so a value added to the enum is named in one place.
// (Methods have a richer table of their own, engine/method_catalog.h.)
#pragma once
#include <cstddef>
#include <stdexcept>
#include <string>
#include <string_view>

namespace sirl {

template <class E>
struct EnumName {
  E value;
  const char* name;
};

// The name of v in `table`; "?" for a value the table lacks (a cast integer).
template <class E, std::size_t n>
const char* name_in(const EnumName<E> (&table)[n], E v) {
  for (const EnumName<E>& e : table)
    if (e.value == v) return e.name;
  return "?";
}

// The value named `name`; std::invalid_argument "unknown <what> '<name>' (expected a, b or c)".
template <class E, std::size_t n>
E value_named(const EnumName<E> (&table)[n], std::string_view name, const char* what) {
  std::string known;
  for (std::size_t i = 0; i < n; ++i) {
    if (name == table[i].name) return table[i].value;
    known += (i == 0 ? "" : i + 1 == n ? " or " : ", ") + std::string(table[i].name);
  }
  throw std::invalid_argument("unknown " + std::string(what) + " '" + std::string(name) +
                              "' (expected " + known + ")");
}

}  // namespace sirl
