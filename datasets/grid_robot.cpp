#include "datasets/grid_robot.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace sirl {

void validate(const GridConfig& c) {
  if (c.size != 5)
    throw std::invalid_argument("grid size must be 5 (9-state corner-to-corner paths), got " +
                                std::to_string(c.size));
  for (const auto& o : {c.obstacle1, c.obstacle2, c.laptop})
    if (o[0] < 0 || o[0] >= c.size || o[1] < 0 || o[1] >= c.size)
      throw std::invalid_argument("grid object (" + std::to_string(o[0]) + ", " +
                                  std::to_string(o[1]) + ") lies outside the " +
                                  std::to_string(c.size) + "x" + std::to_string(c.size) + " grid");
  // Two objects on one cell would make two features one (their distances coincide everywhere).
  const std::array<std::array<int, 2>, 3> objects{c.obstacle1, c.obstacle2, c.laptop};
  for (int a = 0; a < 3; ++a)
    for (int b = a + 1; b < 3; ++b)
      if (objects[a] == objects[b])
        throw std::invalid_argument("grid objects must sit on different cells: two are at (" +
                                    std::to_string(objects[a][0]) + ", " +
                                    std::to_string(objects[a][1]) + ")");
}

std::array<float, 4> grid_features(const GridConfig& c,
                                   const std::array<std::array<int, 2>, kGridStates>& cells,
                                   int angle_deg) {
  std::array<float, 4> f{};
  const std::array<std::array<int, 2>, 3> objects{c.obstacle1, c.obstacle2, c.laptop};
  for (int o = 0; o < 3; ++o) {
    double s = 0;
    for (const auto& p : cells)
      s += std::hypot(double(p[0] - objects[o][0]), double(p[1] - objects[o][1]));
    f[o] = float(s / kGridStates);
  }
  f[3] = float(std::abs(angle_deg));
  return f;
}

Dataset make_grid_dataset(const GridConfig& c) {
  validate(c);
  Dataset d;
  d.env = "grid";
  d.input_dim = kGridInputDim;
  d.input_description =
      "9 states x (x, y) in cells/(size-1) in [0,1], then end-effector angle/90 deg in [-1,1]";
  d.feature_names = {"obstacle1_distance", "obstacle2_distance", "laptop_distance", "abs_angle"};
  d.feature_units = {"cells", "cells", "cells", "degrees"};
  d.object_units = "cells";
  d.object_names = {"obstacle1", "obstacle2", "laptop"};
  d.object_dim = 2;
  for (const auto& o : {c.obstacle1, c.obstacle2, c.laptop}) {
    d.object_positions.push_back(float(o[0]));
    d.object_positions.push_back(float(o[1]));
  }
  const int n = c.size - 1;
  // Ordered corner pairs: (0,0)→(n,n), (n,n)→(0,0), (0,n)→(n,0), (n,0)→(0,n).
  const std::array<std::array<int, 4>, 4> corners{
      {{0, 0, n, n}, {n, n, 0, 0}, {0, n, n, 0}, {n, 0, 0, n}}};
  for (const auto& cp : corners) {
    const int dx = cp[2] > cp[0] ? 1 : -1, dy = cp[3] > cp[1] ? 1 : -1;
    // Every choice of which 4 of the 8 moves go along x (bit set) is one monotone path.
    for (int mask = 0; mask < 256; ++mask) {
      if (__builtin_popcount(mask) != n) continue;
      std::array<std::array<int, 2>, kGridStates> cells;
      cells[0] = {cp[0], cp[1]};
      for (int m = 0; m < 2 * n; ++m) {
        cells[m + 1] = cells[m];
        if (mask >> m & 1)
          cells[m + 1][0] += dx;
        else
          cells[m + 1][1] += dy;
      }
      for (int angle : kGridAngles) {
        for (const auto& p : cells) {
          d.inputs.push_back(float(p[0]) / n);
          d.inputs.push_back(float(p[1]) / n);
        }
        d.inputs.push_back(float(angle) / 90.f);
        const auto f = grid_features(c, cells, angle);
        d.features_raw.insert(d.features_raw.end(), f.begin(), f.end());
        ++d.count;
      }
    }
  }
  normalise_features(d);
  return d;
}

Dataset make_grid2_dataset(const GridConfig& c) {
  Dataset g = make_grid_dataset(c);
  Dataset d = g;
  d.env = "grid2";
  constexpr int kKeep[] = {2, 3};  // laptop_distance, abs_angle of the full GridRobot's four
  d.feature_names.clear();
  d.feature_units.clear();
  d.features_raw.clear();
  for (int f : kKeep) {
    d.feature_names.push_back(g.feature_names[f]);
    d.feature_units.push_back(g.feature_units[f]);
  }
  for (int64_t i = 0; i < g.count; ++i)
    for (int f : kKeep) d.features_raw.push_back(g.features_raw[size_t(i) * 4 + f]);
  d.object_names = {"laptop"};
  d.object_positions = {float(c.laptop[0]), float(c.laptop[1])};
  normalise_features(d);
  return d;
}

}  // namespace sirl
