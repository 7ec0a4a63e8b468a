// The nominal kinematics of the machine as the description states it: the
// kinematics type, its pivots (rt::AcTrtParams, LinuxCNC's xyzac-trt-kins
// pins) and the tool the program was written for. The
// controller's inverse kinematics and the true machine both start from here;
// the true machine adds its errors (rotary_location, tool_*_error, ...).
#pragma once

#include "truecut/rt/core/kinematics_ac.hpp"

namespace truecut::sim {

enum class KinematicsType { kXyzacTrt };

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

// The description's nominal kinematics. The machine's geometry is the
// struct the real-time side uses (rt::AcTrtParams: pivots as in
// docs/kinematics.md, joint readings of a zero-length tool touching the
// pivot, machine frame, mm; directions), so the controller and the simulator
// read one set of parameters. What the simulator adds is its own: the
// kinematics type of the file and the nominal tool.
//
// One place per parameter: the description holds the pivots and
// conventional_directions in `ac`; the tool length in `tool.length_mm`; the
// A travel in joint A (MachineParams::joints). ac.tool_length_mm,
// ac.a_min_deg, ac.a_max_deg and ac.singular_tilt_deg are therefore not part
// of the description: they stay at rt's defaults (the file has no key for
// them), and nominal_ac_params() (true_tool_pose.hpp) fills in the tool
// length and the A travel for the controller.
struct KinematicsParams {
  KinematicsType type = KinematicsType::kXyzacTrt;
  rt::AcTrtParams ac;
  NominalTool tool;
  bool operator==(const KinematicsParams&) const = default;
};

}  // namespace truecut::sim
