#include "experiment/suggest.h"

#include <algorithm>
#include <cctype>

namespace sirl {

int edit_distance(const std::string& a, const std::string& b) {
  const auto lower = [](char c) { return char(std::tolower(static_cast<unsigned char>(c))); };
  const size_t n = a.size(), m = b.size();
  // d[i][j]: distance between a's first i and b's first j characters, rows kept three at a time.
  std::vector<std::vector<int>> d(n + 1, std::vector<int>(m + 1));
  for (size_t i = 0; i <= n; ++i) d[i][0] = int(i);
  for (size_t j = 0; j <= m; ++j) d[0][j] = int(j);
  for (size_t i = 1; i <= n; ++i)
    for (size_t j = 1; j <= m; ++j) {
      const int cost = lower(a[i - 1]) == lower(b[j - 1]) ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && lower(a[i - 1]) == lower(b[j - 2]) &&
          lower(a[i - 2]) == lower(b[j - 1]))
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);  // two neighbours swapped
    }
  return d[n][m];
}

std::string closest_name(const std::string& typed, const std::vector<std::string>& known) {
  // A name longer than any command or profile is no typo of one (and would cost |a|·|b|).
  if (typed.empty() || typed.size() > 64) return "";
  const int limit = std::min(2, std::max(1, int(typed.size()) / 3));
  std::string best;
  int best_d = limit + 1;
  bool tie = false;
  for (const std::string& k : known) {
    if (k.size() > 64) continue;
    const int d = edit_distance(typed, k);
    if (d < best_d) {
      best = k;
      best_d = d;
      tie = false;
    } else if (d == best_d && k != best) {
      tie = true;
    }
  }
  return best_d <= limit && !tie ? best : "";
}

std::string did_you_mean(const std::string& typed, const std::vector<std::string>& known) {
  const std::string best = closest_name(typed, known);
  return best.empty() ? "" : " (did you mean '" + best + "'?)";
}

}  // namespace sirl
