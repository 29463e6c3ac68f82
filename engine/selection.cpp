#include "engine/selection.h"

#include <stdexcept>

namespace sirl {

const char* selection_name(Selection s) {
  switch (s) {
    case Selection::uniform:
      return "uniform";
    case Selection::vote:
      return "vote";
    case Selection::infogain:
      return "infogain";
  }
  return "?";
}

Selection parse_selection(const std::string& name) {
  for (Selection s : {Selection::uniform, Selection::vote, Selection::infogain})
    if (name == selection_name(s)) return s;
  throw std::invalid_argument("unknown query selection '" + name +
                              "' (expected uniform, vote or infogain)");
}

}  // namespace sirl
