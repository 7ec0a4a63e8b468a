// The simulated machine's joints, one servo period at a time: what the
// machine_joints HAL component runs, and what the diagnosis re-simulates.
//
// Per joint: servo_lag on → the drive dynamic of servo_model.hpp, otherwise
// the joint is ideal (motor at the command, encoder reads the command).
// Table side (pos_true) = backlash(motor) + pitch_error(motor) + thermal δ.
// The three linear slides' true positions then get the geometric errors
// (squareness, straightness) → xyz_true, and xyz_true with the true A and C
// go through the true kinematics (true_tool_pose.hpp: rotary_location,
// tool_length_error) → the true TCP and tool axis in the workpiece frame.
// Last, the cutting force bends the tool (tool_deflection: TCP shift and
// axis tilt) and the part (workpiece_deflection: TCP shift relative to the
// workpiece frame). The force is the cutting stage's output of the previous
// cycle, so the deflection lags the force by one period (quasi-static).
//
// Sampling: outputs of cycle k describe the machine at t_k, the instant the
// command cmd_k belongs to (the encoder is read before the drive acts on
// cmd_k); the step then advances the state to t_(k+1).
#pragma once

#include <array>
#include <cstdint>
#include <type_traits>

#include "truecut/sim/machine_description.hpp"
#include "truecut/sim/servo_model.hpp"
#include "truecut/sim/true_tool_pose.hpp"

namespace truecut::sim {

struct MachineInputs {
  std::array<double, kJointCount> pos_cmd{};  // mm, deg
  double spindle_power_kw = 0.0;
  std::array<double, 3> cut_force_n{};     // cutting force on the tool, workpiece frame, N
  std::array<double, 3> cut_contact_mm{};  // where it acts (contact centroid), workpiece frame
  // The nominal tool in the spindle (tool table / G43 length), replacing the
  // description's kinematics.tool when tool_given; the effects' tool errors
  // apply to it. Lets one machine change tools during a program.
  bool tool_given = false;
  NominalTool tool;
};

struct MachineOutputs {
  std::array<double, kJointCount> pos_act{};   // encoder (motor side)
  std::array<double, kJointCount> pos_true{};  // table side along the joint
  std::array<double, kJointCount> vel_act{};   // motor velocity, unit/s
  std::array<double, kJointCount> f_error{};   // cmd − encoder, as the drive sees it
  std::array<double, 3> xyz_true{};            // linear slides with geometric errors, mm
  std::array<double, 3> tcp_true{};            // true TCP (tool tip), workpiece frame, mm
  std::array<double, 3> tool_axis_true{};      // true tool axis, workpiece frame, TCP → spindle
  std::array<double, 3> tool_deflection_mm{};  // tool tip shift by tool_deflection (in tcp_true)
  std::array<double, 3> workpiece_deflection_mm{};
  TrueTool tool_true;  // the real cutter in the spindle this cycle  // tool shift relative to the
                       // bent part
  bool fault = false;  // latched: a non-finite input was seen (and held)
  bool limit_fault = false;  // latched: a command left the joint's travel
};

struct MachineState {
  std::array<ServoState, kJointCount> joints{};
  std::array<double, kJointCount> thermal_mm{};
  double spindle_power_kw = 0.0;
  std::array<double, 3> cut_force_n{};  // last finite inputs
  std::array<double, 3> cut_contact_mm{};
  uint64_t cycles = 0;
  bool started = false;
  bool fault = false;
  bool limit_fault = false;
  // The drives' one-step maps of the periods last seen (servo_linear_step.hpp):
  // what makes a period cheap, never what it computes.
  std::array<ServoLinearCache, kJointCount> servo_linear{};
};

class MachineModel {
 public:
  MachineModel() = default;  // every joint ideal, no effects
  explicit MachineModel(const MachineParams& params);

  const MachineParams& params() const noexcept { return params_; }
  const ServoParams& servo(int joint) const noexcept { return servo_[joint]; }
  bool dynamic(int joint) const noexcept { return params_.effects.servo_lag.active(joint); }
  const TrueKinematics& true_kinematics() const noexcept { return kinematics_; }
  const TrueTool& true_tool() const noexcept { return tool_; }
  // L of tool_deflection: its stickout_mm, or the true tool length.
  double tool_stickout_mm() const noexcept { return stickout_mm_; }

  // One servo period. The first call places every joint at its command.
  void step(MachineState& state, const MachineInputs& in, double period_s,
            MachineOutputs& out) const noexcept;

  // Joint j alone (its drive, backlash, pitch error and thermal drift), as
  // step() advances it: a joint's motion depends on no other joint. Writes
  // out.pos_act, pos_true, vel_act, f_error of joint j only (no geometric
  // errors, no tool pose); `state` must be stepped for this joint only. The
  // diagnosis re-simulates joint by joint with it, bit for bit as step().
  void step_joint(int joint, MachineState& state, double pos_cmd, double spindle_power_kw,
                  double period_s, MachineOutputs& out) const noexcept;

 private:
  // The two halves of a joint's period in step(): its outputs at the start
  // of the period, then the advance to the end.
  void joint_outputs(int joint, MachineState& state, double cmd, double period_s,
                     MachineOutputs& out) const noexcept;
  void advance_joint(int joint, MachineState& state, double cmd, double period_s) const noexcept;

  MachineParams params_;
  std::array<ServoParams, kJointCount> servo_{};
  TrueKinematics kinematics_{};
  TrueTool tool_{};
  double stickout_mm_ = 0.0;
};
static_assert(std::is_trivially_destructible_v<MachineModel>);
static_assert(std::is_trivially_destructible_v<MachineState>);

// The servo parameters of one joint as the description sets them.
ServoParams servo_params(const MachineParams& params, int joint);

}  // namespace truecut::sim
