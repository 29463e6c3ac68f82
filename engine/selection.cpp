#include "engine/selection.h"

#include "datasets/enum_names.h"

namespace sirl {

namespace {
constexpr EnumName<Selection> kSelectionNames[] = {
    {Selection::uniform, "uniform"}, {Selection::vote, "vote"}, {Selection::infogain, "infogain"}};
}  // namespace

const char* selection_name(Selection s) {
  return name_in(kSelectionNames, s);
}

Selection parse_selection(const std::string& name) {
  return value_named(kSelectionNames, name, "query selection");
}

}  // namespace sirl
