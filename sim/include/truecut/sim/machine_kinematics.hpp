// The nominal kinematics of the machine as the description states it: the
// kinematics type, its pivots (the fields of rt::AcTrtParams, LinuxCNC's
// xyzac-trt-kins pins) and the tool the program was written for. The
// controller's inverse kinematics and the true machine both start from here;
// the true machine adds its errors (rotary_location, tool_*_error, ...).
#pragma once

namespace truecut::sim {

enum class KinematicsType { XyzacTrt };

// The tool the program assumes. The TCP is the tool tip on the tool axis,
// length_mm below the spindle gauge point (LinuxCNC's tool length offset).
struct NominalTool {
  double length_mm = 0.0;         // gauge point to tip, >= 0
  double radius_mm = 0.0;         // cutter radius, >= 0
  double corner_radius_mm = 0.0;  // 0: flat end mill; = radius_mm: ball end mill
  bool operator==(const NominalTool&) const = default;
};

inline bool is_ball_end_mill(const NominalTool& t) noexcept {
  return t.radius_mm > 0.0 && t.corner_radius_mm == t.radius_mm;
}

// Pivots as in docs/kinematics.md: joint readings of a zero-length tool
// touching the pivot, machine frame, mm.
struct KinematicsParams {
  KinematicsType type = KinematicsType::XyzacTrt;
  double x_rot_point_mm = 0.0;  // C axis at A = 0, X
  double y_rot_point_mm = 0.0;  // C axis at A = 0, Y
  double z_rot_point_mm = 0.0;  // reference height of the pivots
  double y_offset_mm = 0.0;     // A axis relative to the C axis, Y
  double z_offset_mm = 0.0;     // A axis relative to z_rot_point, Z
  bool conventional_directions = false;
  NominalTool tool;
  bool operator==(const KinematicsParams&) const = default;
};

}  // namespace truecut::sim
