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
// and the slope stands out of its noise (min_slope_significance), the
// slope becomes the rotation w = b (k x n) (rad; k the axis, n the mean
// normal across the axis, unit): a rotation that moves the flank at height h
// by b h along n. Elsewhere the rotation is 0 (a face cut by the tip, a
// corner, a slope within the scan's noise): a sample that pins the field's
// rotation to zero there. Each
// point's translation is what is left at the tip: its vector minus
// w x (h k).
//
// The rotation is then cut to what the machine can give
// (realisable_rotation): on a table-table A/C machine the tool axis tilts
// along its meridian (A) at any angle, but sideways (C) only as far as A has
// tilted the table; a tool standing at A = 0 cannot tilt about the line
// perpendicular to A's. What the machine cannot give is left out before the
// translations are formed, so that those points keep the constant shift
// that fits them best (the mean over their height), exactly as without a
// rotation, instead of a translation at the tip that assumed a tilt.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <span>
#include <vector>

#include "truecut/offline/field_fit.hpp"

namespace truecut::offline {

// Which tool orientations the machine can reach near each pose.
enum class RotaryKinematics {
  kAcTableTable,    // A about X, C about Z on the table: truecut's machine, xyzac-trt-kins
  kAnyOrientation,  // every tilt (a head with two free axes; tcp mode into a controller
                    // whose own kinematics has no singular pose near the path)
};

struct ToolRotationOptions {
  RotaryKinematics kinematics = RotaryKinematics::kAcTableTable;
  double min_height_spread_mm = 1.0;
  int min_points = 3;
  double max_normal_spread_deg = 20.0;
  // A slope smaller than this many of its standard errors (the residuals'
  // serial correlation taken in; Student's t at the same level) is taken
  // for noise: no rotation there. 0: every slope is used.
  double min_slope_significance = 2.0;
};

// One compensation point as placed at a tool-path sample.
struct PlacedVector {
  std::uint32_t sample = 0;                          // tool-path sample index
  Eigen::Vector3d tcp_mm = Eigen::Vector3d::Zero();  // the sample's tip
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();   // unit, tip towards spindle
  double c_deg = 0.0;  // the C word at the sample: where A = 0 it says which way A tilts
  Eigen::Vector3d point_mm = Eigen::Vector3d::Zero();   // the compensation point
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();    // its unit nominal normal
  Eigen::Vector3d vector_mm = Eigen::Vector3d::Zero();  // its compensation vector
};

struct ToolRotationEstimate {
  // One per tool-path sample with points: position = the tip, vector_mm =
  // the rotation (rad), whole-vector samples (zero where the slope is
  // within the noise).
  std::vector<FitSample> rotations;
  // Per placed point (same order): the translation at the tip.
  std::vector<Eigen::Vector3d> translations_mm;
  std::int64_t tilted_samples = 0;  // samples given a rotation (slope fitted)
  // Samples whose fitted rotation the machine cannot give in full, and the
  // largest part of one left out, rad.
  std::int64_t insignificant_samples = 0;  // a slope within the noise: no rotation
  std::int64_t cut_samples = 0;
  double max_left_out_rad = 0.0;
};

// The part of the rotation vector w (rad, workpiece frame) that the machine
// can give to a tool with unit axis k (sin A sin C, sin A cos C, cos A) at
// the C word c_deg: the tilt dk = w x k split along the meridian (what A
// turns: d k / dA) and across it (what C turns: d k / dC, of length sin A).
// kAcTableTable keeps the meridian part, and the sideways part only where
// sin A >= rt::comp::kRotaryDampingStart (sin 2 deg; below it truecut_comp
// would damp it away); the result is k x (the kept tilt), perpendicular to
// k. kAnyOrientation returns w's part perpendicular to k.
Eigen::Vector3d realisable_rotation(const Eigen::Vector3d& w_rad, const Eigen::Vector3d& axis,
                                    double c_deg, RotaryKinematics kinematics);

// Each point's translation at the tip under the rotation `rotation_of(sample
// tip, axis, c_deg)` of its sample (what the fitted field gives there): its
// vector minus w x (h k).
template <class RotationAt>
std::vector<Eigen::Vector3d> translations_at_tip(std::span<const PlacedVector> placed,
                                                 RotationAt&& rotation_of) {
  std::vector<Eigen::Vector3d> out(placed.size());
  for (std::size_t i = 0; i < placed.size(); ++i) {
    const PlacedVector& p = placed[i];
    const Eigen::Vector3d w = rotation_of(p);
    out[i] = p.vector_mm - w.cross((p.point_mm - p.tcp_mm).dot(p.axis) * p.axis);
  }
  return out;
}

// Deterministic; O(points log points).
ToolRotationEstimate estimate_tool_rotation(std::span<const PlacedVector> placed,
                                            const ToolRotationOptions& options = {});

}  // namespace truecut::offline
