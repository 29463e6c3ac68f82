// GridRobot (paper §4.1): a 5×5 grid with two obstacles and a laptop. Ξ holds every 9-state
// path of unit moves between opposite corners (4 ordered corner pairs; 8 moves between corners
// 8 cells apart must all head toward the goal, so each pair has C(8,4) = 70 paths) times the
// end-effector angle at the end state ∈ {−90, −60, −30, 0, 30, 60, 90}°: 4·70·7 = 1960.
// Objects do not block paths: the features measure proximity, as in the paper.
//
// Input vector (19 floats): for each state s = 0..8, (x_s, y_s)/(size − 1) ∈ [0, 1], then
// angle/90° ∈ [−1, 1].
// True features φ* (raw units): mean over the 9 states of the Euclidean distance (in cells) to
// obstacle 1, obstacle 2 and the laptop, and |angle| in degrees; normalised min-max over Ξ.
#pragma once
#include <array>
#include <cstdint>

#include "datasets/dataset.h"

namespace sirl {

struct GridConfig {
  int size = 5;
  // Cells (x, y), 0-based from the lower-left corner. Defaults: the two obstacles sit off the
  // diagonals and the laptop in the centre, so every feature varies over Ξ.
  std::array<int, 2> obstacle1{1, 3};
  std::array<int, 2> obstacle2{3, 1};
  std::array<int, 2> laptop{2, 2};
};

inline constexpr int kGridStates = 9;
inline constexpr int kGridInputDim = 2 * kGridStates + 1;
inline constexpr std::array<int, 7> kGridAngles{-90, -60, -30, 0, 30, 60, 90};
inline constexpr int64_t kGridTrajectories = 4 * 70 * 7;

// Throws std::invalid_argument for a size other than 5 (the path length is fixed at 9 states)
// or an object outside the grid.
void validate(const GridConfig& cfg);

Dataset make_grid_dataset(const GridConfig& cfg = {});

// "grid2", the paper's simplified GridRobot (its Fig. 3: "only the laptop and the joint angle"):
// the same Ξ and inputs, no obstacles, and two features, laptop_distance and abs_angle.
Dataset make_grid2_dataset(const GridConfig& cfg = {});

// The 4 raw features of one trajectory given its 9 cells and angle (exposed for tests).
std::array<float, 4> grid_features(const GridConfig& cfg,
                                   const std::array<std::array<int, 2>, kGridStates>& cells,
                                   int angle_deg);

}  // namespace sirl
