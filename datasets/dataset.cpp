#include "datasets/dataset.h"

#include <algorithm>
#include <limits>

namespace sirl {

void normalise_features(Dataset& d) {
  const int F = d.feature_count();
  d.feature_min.assign(F, std::numeric_limits<float>::infinity());
  d.feature_max.assign(F, -std::numeric_limits<float>::infinity());
  for (int64_t i = 0; i < d.count; ++i)
    for (int f = 0; f < F; ++f) {
      const float v = d.features_raw[i * F + f];
      d.feature_min[f] = std::min(d.feature_min[f], v);
      d.feature_max[f] = std::max(d.feature_max[f], v);
    }
  d.features.resize(d.features_raw.size());
  for (int64_t i = 0; i < d.count; ++i)
    for (int f = 0; f < F; ++f) {
      const float span = d.feature_max[f] - d.feature_min[f];
      d.features[i * F + f] =
          span > 0 ? (d.features_raw[i * F + f] - d.feature_min[f]) / span : 0.f;
    }
}

}  // namespace sirl
