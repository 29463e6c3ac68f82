#include "engine/convergence.h"

#include <algorithm>
#include <cmath>

namespace sirl {

Convergence check_convergence(const std::vector<float>& curve, double rel_tol, double abs_tol) {
  Convergence c;
  const int E = int(curve.size());
  if (E < 2) return c;
  c.window = std::max(1, E / 10);
  auto mean = [&](int from, int to) {
    double s = 0;
    for (int i = from; i < to; ++i) s += curve[i];
    return s / (to - from);
  };
  const double b = mean(E - c.window, E), a = mean(E - 2 * c.window, E - c.window);
  const double scale = std::max(std::abs(a), std::abs(b));
  c.relative_change = scale > 0 ? (a - b) / scale : 0.0;
  c.converged =
      std::isfinite(a) && std::isfinite(b) && std::abs(a - b) <= rel_tol * scale + abs_tol;
  return c;
}

}  // namespace sirl

namespace sirl {

const TpaStopRule* find_tpa_stop_rule(std::string_view name) {
  for (const TpaStopRule& r : kTpaStopRules)
    if (name == r.name) return &r;
  return nullptr;
}

bool tpa_stop_may_end_early(std::string_view name) {
  const TpaStopRule* r = find_tpa_stop_rule(name);
  return r && (r->stops_unfrozen || r->stops_frozen);
}

std::string tpa_stop_rule_list() {
  std::string s;
  const size_t n = std::size(kTpaStopRules);
  for (size_t i = 0; i < n; ++i) {
    if (i > 0) s += i + 1 == n ? " or " : ", ";
    s += std::string("\"") + kTpaStopRules[i].name + "\" (" + kTpaStopRules[i].doc + ")";
  }
  return s;
}

bool stops_after(const StopRule& rule, const float* curve, int e) {
  if (!rule.converged || e < std::max(2, rule.min_epochs)) return false;
  return check_convergence(std::vector<float>(curve, curve + e), rule.rel_tol).converged;
}

}  // namespace sirl
