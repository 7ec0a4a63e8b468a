// Matrix mode with every pass taking the compensation of every point its
// cutting part sweeps (docs/rewrite.md, "Every pass that sweeps a point"),
// as the field stage's tool-centre placement does: the source's blend
// (eqs. 2-5, 3 nearest points) is evaluated at query points spread over the
// cutting part of the tool, and the blends are averaged.
//
//   peripheral: the flank, one cutting circle of radius R every `band_mm`
//     from the tip up to `length_mm` along the axis (a wall cut in levels
//     is swept again by every level below it);
//   face: the bottom disc, query points on rings `band_mm` apart up to the
//     rim, about `band_mm` apart on each ring (every pass whose disc covers a
//     point cuts it).
// A ball end mill cuts the surface at one contact point: its rule stays the
// source's (NeighbourSearch::nearest).
#pragma once

#include <Eigen/Core>
#include <array>

#include "neighbours.hpp"

namespace truecut::interp::rewrite {

struct SweptCorrection {
  Eigen::Vector3d correction_mm = Eigen::Vector3d::Zero();  // mean of the blends
  int blends = 0;                                           // 0: no point within reach
  std::array<int, 4> blends_by_points{};                    // [k]: blends from k points
};

// Throws std::logic_error for a ball search.
SweptCorrection swept_correction(const NeighbourSearch& search, const ToolPoint& tool,
                                 double length_mm, double band_mm);

}  // namespace truecut::interp::rewrite
