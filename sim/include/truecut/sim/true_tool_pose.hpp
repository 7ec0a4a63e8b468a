// The true tool pose: where the tool really is relative to the workpiece,
// from the joints' true (table-side) positions through the machine's true
// kinematics — the nominal xyzac-trt chain (rt/kinematics_ac.hpp) with the
// rotary axis lines where rotary_location puts them, the linear slides'
// geometric errors already in xyz, and the real tool's length.
//
//   t   = xyz_true − L_true · e_z                      TCP in the machine frame
//   tcp = Q_C + R(u_C, −γ) · ( R(u_A, −α) · (t − Q_A) + (Q_A − Q_C) )
//   axis = R(u_C, −γ) · R(u_A, −α) · e_z
//   α = σ · (A + E_A0A),  γ = σ · (C + E_C0C),  σ = −1 with conventional directions
//
// R(u, θ) is the right-handed rotation by θ about the unit vector u. With
// every effect off (Q = P, u_A = e_x, u_C = e_z, L_true = L) this is
// rt::forward_ac of the nominal parameters. Equations and signatures:
// docs/machine-model.md.
#pragma once

#include <array>

#include "truecut/rt/core/kinematics_ac.hpp"
#include "truecut/sim/machine_description.hpp"

namespace truecut::sim {

// The cutter the spindle really carries (the nominal tool plus
// tool_length_error and tool_radius_error). The cutting stage removes
// material with it.
struct TrueTool {
  double length_mm = 0.0;  // gauge point to tip
  double radius_mm = 0.0;
  double corner_radius_mm = 0.0;
  bool operator==(const TrueTool&) const = default;
};

// The true kinematic chain, built once from a description and used every
// servo cycle (plain data, machine frame, mm).
struct TrueKinematics {
  std::array<double, 3> a_point_mm{};          // Q_A: a point of the A axis line
  std::array<double, 3> a_direction{1, 0, 0};  // u_A, unit
  std::array<double, 3> c_point_mm{};          // Q_C: a point of the C axis line (cradle frame)
  std::array<double, 3> c_direction{0, 0, 1};  // u_C, unit
  double a_zero_rad = 0.0;                     // E_A0A, added to the A reading
  double c_zero_rad = 0.0;                     // E_C0C, added to the C reading
  bool conventional_directions = false;
  double tool_length_mm = 0.0;  // L_true
};

// The parameters the controller's kinematics uses: the description's nominal
// pivots and tool length; the A travel of joint a when it is listed.
rt::AcTrtParams nominal_ac_params(const MachineParams& params) noexcept;

TrueTool true_tool(const MachineParams& params) noexcept;
// The real cutter for a nominal tool (the tool in the spindle): nominal +
// tool_length_error + tool_radius_error of the effects.
TrueTool true_tool(const NominalTool& nominal, const Effects& effects) noexcept;

TrueKinematics true_kinematics(const MachineParams& params) noexcept;

// Pure: no allocation, no exceptions, fixed work. Angles in degrees, any
// number of turns.
rt::ToolPose true_tool_pose(const TrueKinematics& kinematics,
                            const std::array<double, 3>& xyz_true_mm, double a_true_deg,
                            double c_true_deg) noexcept;

}  // namespace truecut::sim
