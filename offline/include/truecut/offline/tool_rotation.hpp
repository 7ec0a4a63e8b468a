// The tool-orientation part of a correction (issue 19, point 6;
// docs/offline.md, "Tool rotation"). Where a tool's flank cuts a wall over a
// height h along its axis, the correction the wall needs may change with h
// (a shaft that bends more at its free end, a tool that deflects more at
// full engagement): a field at the tool centre can only shift the tool, the
// same at every height, while a rotation of the tool about its tip moves the
// flank at height h by h times the angle.
//
// For each tool-path sample (one tip, one axis) and the compensation points
// placed at it, the normal component of their compensation vectors is
// fitted by a line in h, the height above the tip along the axis:
//   s(h) = a + b h.
// Where the points span at least min_height_spread_mm along the axis and
// face one way (every normal within max_normal_spread_deg of their mean),
// the slope becomes the rotation w = b (k x n) (rad; k the axis, n the mean
// normal across the axis, unit): a rotation that moves the flank at height h
// by b h along n. Elsewhere the rotation is 0 (a face cut by the tip, a
// corner): a sample that pins the field's rotation to zero there. Each
// point's translation is what is left at the tip: its vector minus
// w x (h k).
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <span>
#include <vector>

#include "truecut/offline/field_fit.hpp"

namespace truecut::offline {

struct ToolRotationOptions {
  double min_height_spread_mm = 1.0;
  int min_points = 3;
  double max_normal_spread_deg = 20.0;
};

// One compensation point as placed at a tool-path sample.
struct PlacedVector {
  std::uint32_t sample = 0;                             // tool-path sample index
  Eigen::Vector3d tcp_mm = Eigen::Vector3d::Zero();     // the sample's tip
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();      // unit, tip towards spindle
  Eigen::Vector3d point_mm = Eigen::Vector3d::Zero();   // the compensation point
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();    // its unit nominal normal
  Eigen::Vector3d vector_mm = Eigen::Vector3d::Zero();  // its compensation vector
};

struct ToolRotationEstimate {
  // One per tool-path sample with points: position = the tip, vector_mm =
  // the rotation (rad), whole-vector samples.
  std::vector<FitSample> rotations;
  // Per placed point (same order): the translation at the tip.
  std::vector<Eigen::Vector3d> translations_mm;
  std::int64_t tilted_samples = 0;  // samples given a rotation (slope fitted)
};

// Deterministic; O(points log points).
ToolRotationEstimate estimate_tool_rotation(std::span<const PlacedVector> placed,
                                            const ToolRotationOptions& options = {});

}  // namespace truecut::offline
