// How a variant's similarity queries are chosen: uniformly at random (the paper) or by an active
// rule (engine/active_queries.h). A name of its own so the method catalog can name variants
// without depending on the active-query machinery.
#pragma once
#include <string>

namespace sirl {

enum class Selection { uniform, vote, infogain };
// "uniform", "vote", "infogain" and back (throws std::invalid_argument listing the names).
const char* selection_name(Selection s);
Selection parse_selection(const std::string& name);

}  // namespace sirl
