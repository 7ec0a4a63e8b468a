// Kinematics of an A/C table-table (trunnion) 5-axis machine, parameterised
// like LinuxCNC's xyzac-trt-kins. Pure functions: no HAL, no allocation, no
// exceptions; safe to call every servo cycle. Equations: docs/kinematics.md.
//
// Conventions
// - Machine frame: right-handed, fixed to the bed. X, Y, Z joints place the
//   spindle gauge point (a zero-length tool's tip) in this frame; the tool
//   points along -Z, so the tool centre point (TCP) sits at
//   (X, Y, Z - tool_length_mm).
// - Workpiece frame: carried by the C table; it coincides with the machine
//   frame when A = C = 0. Fixture offsets (G54...) are not handled here.
// - A turns the trunnion about an axis parallel to machine X through
//   (y_rot_point + y_offset, z_rot_point + z_offset); C turns the table about
//   an axis that, at A = 0, is parallel to machine Z through
//   (x_rot_point, y_rot_point). Pivot coordinates are joint readings of a
//   zero-length tool touching the pivot.
// - Directions (conventional_directions = false, LinuxCNC's default): a
//   positive joint angle turns the table right-handedly about +X (A) and +Z
//   (C). conventional_directions = true reverses both, so that positive
//   angles turn the tool right-handedly relative to the workpiece (ISO 841).
// - Tool axis: unit vector from the TCP towards the spindle, in the workpiece
//   frame. With the default directions it is (sinA sinC, sinA cosC, cosA).
// - Relation to LinuxCNC with the same pins: its world position equals our
//   TCP plus (0, 0, tool_length_mm), because its world Z carries the tool
//   length offset.
#pragma once

// Part of the real-time core: include "truecut/rt/comp.hpp" (std and Eigen only).

#include <Eigen/Core>

namespace truecut::rt {

struct AcTrtParams {
  double x_rot_point_mm = 0.0;  // C axis, X (machine frame, A = 0)
  double y_rot_point_mm = 0.0;  // C axis, Y (machine frame, A = 0)
  double z_rot_point_mm = 0.0;  // reference height; only z_rot_point + z_offset matters
  double y_offset_mm = 0.0;     // A axis relative to the C axis, Y
  double z_offset_mm = 0.0;     // A axis relative to z_rot_point, Z
  double tool_length_mm = 0.0;  // gauge point to TCP, along -Z
  bool conventional_directions = false;
  // Travel of A used to choose between the two solutions of the inverse.
  double a_min_deg = -180.0;
  double a_max_deg = 180.0;
  // Below this tilt the C angle is taken from the hint instead of from the
  // tool axis (orientation error at most sin(singular_tilt_deg)).
  double singular_tilt_deg = 1e-8;
  bool operator==(const AcTrtParams&) const = default;
};

struct AcJoints {
  double x_mm = 0.0;
  double y_mm = 0.0;
  double z_mm = 0.0;
  double a_deg = 0.0;
  double c_deg = 0.0;
};

// Tool-centre point and tool axis in the workpiece frame.
struct ToolPose {
  Eigen::Vector3d tcp_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  // unit, TCP -> spindle
};

enum class AcIkStatus {
  kOk,
  kSingular,      // tilt below singular_tilt_deg: C kept from the hint
  kOutOfLimits,   // neither A solution lies within [a_min_deg, a_max_deg]
  kInvalidInput,  // non-finite pose or hint, or a zero tool axis
};

struct AcIkResult {
  AcJoints joints;  // for invalid_input: the hint, unchanged
  AcIkStatus status = AcIkStatus::kOk;
};

const char* to_string(AcIkStatus status) noexcept;

ToolPose forward_ac(const AcTrtParams& params, const AcJoints& joints) noexcept;

// Of the two (A, C) solutions, returns the one closest to `hint` (normally
// the previous cycle's joints) among those within the A travel; C is unwound
// to within 180 degrees of hint.c_deg. The tool axis need not be exactly
// unit: it is normalised.
AcIkResult inverse_ac(const AcTrtParams& params, const ToolPose& pose,
                      const AcJoints& hint) noexcept;

}  // namespace truecut::rt
