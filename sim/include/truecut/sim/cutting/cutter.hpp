// The cutter of the cutting model: an end mill as a solid of revolution, and
// its pose in the workpiece frame. See docs/cutting.md.
#pragma once

#include <Eigen/Core>

namespace truecut::sim::cutting {

// Flat end mill: corner_radius_mm = 0. Ball end mill: corner_radius_mm =
// radius_mm. Bull-nose: in between. The cutting part reaches from the tip to
// flute_length_mm up the axis; above it the model has no tool.
struct CutterShape {
  double radius_mm = 0;
  double corner_radius_mm = 0;
  double flute_length_mm = 0;
};

// Tool tip (the programmed point: flat bottom of an end mill, lowest point of
// a ball mill) and the unit tool axis (tip → spindle), workpiece frame.
struct CutterPose {
  Eigen::Vector3d tip_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
};

// radius > 0, 0 ≤ corner ≤ radius, flute length ≥ corner radius, all finite.
bool valid(const CutterShape& shape) noexcept;
// Finite tip, finite axis with a length in [0.5, 2] (normalised by the model).
bool valid(const CutterPose& pose) noexcept;

}  // namespace truecut::sim::cutting
