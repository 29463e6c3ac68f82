#include "datasets/simulated_human.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

namespace sirl {

void validate(const Teacher& t, int F) {
  if (!(t.beta >= 0))
    throw std::invalid_argument("teacher beta must be >= 0 (inf = perfect oracle, 0 = random)");
  if (!(t.mistake >= 0 && t.mistake <= 1))
    throw std::invalid_argument("teacher mistake probability must be in [0, 1]");
  if (!(t.skip >= 0) || !(t.equal >= 0))
    throw std::invalid_argument("teacher skip/equal thresholds must be >= 0");
  if (!t.mask.empty()) {
    if (int(t.mask.size()) != F)
      throw std::invalid_argument("teacher feature mask has " + std::to_string(t.mask.size()) +
                                  " entries, the environment has " + std::to_string(F) +
                                  " features");
    if (std::none_of(t.mask.begin(), t.mask.end(), [](uint8_t m) { return m != 0; }))
      throw std::invalid_argument("teacher feature mask hides every feature");
  }
}

namespace {
double masked_sqdist(const float* a, const float* b, int F, const std::vector<uint8_t>& mask) {
  double s = 0;
  for (int f = 0; f < F; ++f)
    if (mask.empty() || mask[f]) s += double(a[f] - b[f]) * (a[f] - b[f]);
  return s;
}
}  // namespace

double reward(const float* w, const float* f, int F, const std::vector<uint8_t>& mask) {
  double r = 0;
  for (int k = 0; k < F; ++k)
    if (mask.empty() || mask[k]) r += double(w[k]) * f[k];
  return r;
}

std::optional<TripletAnswer> answer_similarity(const Teacher& t, const float* f1, const float* f2,
                                               const float* f3, int F, Rng& rng) {
  // Pair k and its odd one out: 0 = (1,2 | 3), 1 = (1,3 | 2), 2 = (2,3 | 1).
  static constexpr std::array<TripletAnswer, 3> kPairs{{{0, 1, 2}, {0, 2, 1}, {1, 2, 0}}};
  const std::array<double, 3> d{masked_sqdist(f1, f2, F, t.mask), masked_sqdist(f1, f3, F, t.mask),
                                masked_sqdist(f2, f3, F, t.mask)};
  const double dmin = *std::min_element(d.begin(), d.end()),
               dmax = *std::max_element(d.begin(), d.end());
  if (t.skip > 0 && dmax - dmin < t.skip) return std::nullopt;
  int k = 0;
  if (std::isinf(t.beta)) {
    // Closest pair; with `equal`, a coin flip among the pairs within `equal` of it.
    // Exact ties with equal = 0 go to the first pair in the fixed order above.
    std::array<int, 3> near{};
    int n = 0;
    for (int j = 0; j < 3; ++j)
      if (d[j] - dmin <= t.equal && (t.equal > 0 || d[j] == dmin)) near[n++] = j;
    k = t.equal > 0 && n > 1 ? near[rng.uniform_int(n)] : near[0];
  } else {
    std::array<double, 3> p;
    for (int j = 0; j < 3; ++j) p[j] = std::exp(-t.beta * (d[j] - dmin));
    const double u = rng.uniform() * (p[0] + p[1] + p[2]);
    k = u < p[0] ? 0 : (u < p[0] + p[1] ? 1 : 2);
  }
  if (t.mistake > 0 && rng.uniform() < t.mistake) k = (k + 1 + int(rng.uniform_int(2))) % 3;
  return kPairs[k];
}

std::optional<float> answer_preference(const Teacher& t, const float* w, const float* fa,
                                       const float* fb, int F, Rng& rng) {
  const double diff = reward(w, fa, F, t.mask) - reward(w, fb, F, t.mask);
  if (t.skip > 0 && std::abs(diff) < t.skip) return std::nullopt;
  if (t.equal > 0 && std::abs(diff) < t.equal) return 0.5f;
  float label;
  if (std::isinf(t.beta)) {
    label = diff > 0 ? 1.f : (diff < 0 ? 0.f : 0.5f);
  } else {
    label = rng.uniform() < 1.0 / (1.0 + std::exp(-t.beta * diff)) ? 1.f : 0.f;
  }
  if (t.mistake > 0 && label != 0.5f && rng.uniform() < t.mistake) label = 1.f - label;
  return label;
}

}  // namespace sirl
