#include "truecut/sim/machine_model.hpp"

#include <Eigen/Core>
#include <cmath>
#include <numbers>

namespace truecut::sim {

namespace {

using Vec = Eigen::Vector3d;

Vec vec(const std::array<double, 3>& a) noexcept {
  return {a[0], a[1], a[2]};
}
std::array<double, 3> arr(const Vec& v) noexcept {
  return {v.x(), v.y(), v.z()};
}

// Takes a vector input when all of it is finite; otherwise keeps the last
// one and reports false.
bool take_finite(std::array<double, 3>& held, const std::array<double, 3>& in) noexcept {
  if (!(std::isfinite(in[0]) && std::isfinite(in[1]) && std::isfinite(in[2]))) return false;
  held = in;
  return true;
}

// Force (N) per kg → mm/s²; torque (N·m) per kg·m² → deg/s².
double accel_per_force_over_inertia(int joint) {
  return joint_kind(joint) == JointKind::kLinear ? 1000.0 : 180.0 / std::numbers::pi;
}

}  // namespace

ServoParams servo_params(const MachineParams& params, int joint) {
  const DriveParams& d = params.joints[joint].drive;
  ServoParams s;
  if (const auto* lag = params.effects.servo_lag.active(joint)) {
    s.kv_per_s = lag->kv_per_s;
    s.ff1 = lag->ff1;
  }
  s.vel_kp_per_s = 2.0 * std::numbers::pi * d.vel_bandwidth_hz;
  s.vel_ki_per_s2 = s.vel_kp_per_s / d.vel_integral_time_s;
  s.max_accel = d.max_accel;
  s.encoder_resolution = d.encoder_resolution;
  if (const auto* f = params.effects.reversal_spike.active(joint)) {
    const double k = accel_per_force_over_inertia(joint) / d.inertia;
    s.coulomb_accel = f->coulomb * k;
    s.viscous_per_s = f->viscous * k;
  }
  if (const auto* b = params.effects.backlash.active(joint)) s.backlash_play = b->play;
  return s;
}

MachineModel::MachineModel(const MachineParams& params)
    : params_(params), kinematics_(sim::true_kinematics(params)), tool_(sim::true_tool(params)) {
  for (int j = 0; j < kJointCount; ++j)
    servo_[j] = servo_params(params, j);
  stickout_mm_ = params.effects.tool_deflection.params.stickout_mm.value_or(tool_.length_mm);
}

void MachineModel::step(MachineState& st, const MachineInputs& in, double period_s,
                        MachineOutputs& out) const noexcept {
  const Effects& fx = params_.effects;
  std::array<double, kJointCount> cmd;
  for (int j = 0; j < kJointCount; ++j) {
    cmd[j] = in.pos_cmd[j];
    if (!std::isfinite(cmd[j])) {
      cmd[j] = st.started ? st.joints[j].prev_cmd : 0.0;
      st.fault = true;
    }
  }
  if (std::isfinite(in.spindle_power_kw))
    st.spindle_power_kw = in.spindle_power_kw;
  else
    st.fault = true;
  if (!take_finite(st.cut_force_n, in.cut_force_n)) st.fault = true;
  if (!take_finite(st.cut_contact_mm, in.cut_contact_mm)) st.fault = true;
  if (!st.started) {
    for (int j = 0; j < kJointCount; ++j)
      st.joints[j] = servo_start(cmd[j]);
    st.started = true;
  }

  for (int j = 0; j < kJointCount; ++j)
    joint_outputs(j, st, cmd[j], period_s, out);

  out.xyz_true = apply_geometric_errors(fx.squareness.active(), fx.straightness.active(),
                                        {out.pos_true[kX], out.pos_true[kY], out.pos_true[kZ]});
  TrueKinematics kinematics = kinematics_;
  double stickout_mm = stickout_mm_;
  out.tool_true = tool_;
  const NominalTool& t = in.tool;
  const bool tool_ok = t.length_mm >= 0 && t.radius_mm >= 0 && t.corner_radius_mm >= 0 &&
                       std::isfinite(t.length_mm) && std::isfinite(t.radius_mm) &&
                       std::isfinite(t.corner_radius_mm);
  if (in.tool_given && !tool_ok) st.fault = true;  // the description's tool stays in use
  if (in.tool_given && tool_ok) {
    out.tool_true = sim::true_tool(in.tool, fx);
    kinematics.tool_length_mm = out.tool_true.length_mm;
    stickout_mm = fx.tool_deflection.params.stickout_mm.value_or(out.tool_true.length_mm);
  }
  const rt::ToolPose pose =
      true_tool_pose(kinematics, out.xyz_true, out.pos_true[kA], out.pos_true[kC]);

  // Deflections under the cutting force, about the undeflected true pose.
  const Vec force = vec(st.cut_force_n), contact = vec(st.cut_contact_mm);
  Vec tcp = pose.tcp_mm, axis = pose.axis, tool_shift = Vec::Zero(), part_shift = Vec::Zero();
  if (const auto* e = fx.tool_deflection.active()) {
    const ToolBend bend = tool_bend(e->stiffness_n_per_um, stickout_mm, force, pose.axis,
                                    (contact - pose.tcp_mm).dot(pose.axis));
    tool_shift = bend.tip_mm;
    tcp += tool_shift;
    // The tip leans out along F⊥: the axis (tip → spindle) tilts towards −F⊥.
    axis = pose.axis * std::cos(bend.slope_rad) - bend.direction * std::sin(bend.slope_rad);
  }
  if (const auto* e = fx.workpiece_deflection.active()) {
    part_shift = workpiece_deflection_mm(*e, force, contact);
    tcp += part_shift;
  }
  out.tcp_true = arr(tcp);
  out.tool_axis_true = arr(axis);
  out.tool_deflection_mm = arr(tool_shift);
  out.workpiece_deflection_mm = arr(part_shift);

  // Advance to the end of the period.
  for (int j = 0; j < kJointCount; ++j)
    advance_joint(j, st, cmd[j], period_s);
  ++st.cycles;
  out.fault = st.fault;
  out.limit_fault = st.limit_fault;
}

void MachineModel::joint_outputs(int j, MachineState& st, double cmd, double period_s,
                                 MachineOutputs& out) const noexcept {
  const Effects& fx = params_.effects;
  ServoState& s = st.joints[j];
  const ServoParams& sp = servo_[j];
  const JointParams& jp = params_.joints[j];
  if (!(cmd >= jp.min && cmd <= jp.max)) st.limit_fault = true;

  if (dynamic(j)) {
    const double enc = encoder_reading(sp, s.pos);
    out.pos_act[j] = enc;
    out.f_error[j] = cmd - enc;
    out.vel_act[j] = s.vel;
  } else {
    // Ideal drive: the motor is where it is told, at every instant.
    s.vel = (cmd - s.prev_cmd) / period_s;
    s.pos = cmd;
    s.prev_cmd = cmd;
    s.table =
        sp.backlash_play > 0.0 ? backlash_table_position(s.table, s.pos, sp.backlash_play) : s.pos;
    out.pos_act[j] = cmd;
    out.f_error[j] = 0.0;
    out.vel_act[j] = s.vel;
  }

  double pos_true = s.table;
  if (const auto* e = fx.pitch_error.active(j)) pos_true += pitch_error_mm(*e, s.pos);
  if (fx.thermal_drift.active(j)) pos_true += st.thermal_mm[j];
  out.pos_true[j] = pos_true;
}

void MachineModel::advance_joint(int j, MachineState& st, double cmd,
                                 double period_s) const noexcept {
  if (dynamic(j)) servo_step(servo_[j], st.joints[j], cmd, period_s, st.servo_linear[j]);
  if (const auto* e = params_.effects.thermal_drift.active(j))
    st.thermal_mm[j] =
        thermal_drift_step(*e, st.thermal_mm[j], thermal_drive(*e, st.spindle_power_kw), period_s);
}

void MachineModel::step_joint(int j, MachineState& st, double pos_cmd, double spindle_power_kw,
                              double period_s, MachineOutputs& out) const noexcept {
  double cmd = pos_cmd;
  if (!std::isfinite(cmd)) {
    cmd = st.started ? st.joints[j].prev_cmd : 0.0;
    st.fault = true;
  }
  if (std::isfinite(spindle_power_kw))
    st.spindle_power_kw = spindle_power_kw;
  else
    st.fault = true;
  if (!st.started) {
    st.joints[j] = servo_start(cmd);
    st.started = true;
  }
  joint_outputs(j, st, cmd, period_s, out);
  advance_joint(j, st, cmd, period_s);
  ++st.cycles;
  out.fault = st.fault;
  out.limit_fault = st.limit_fault;
}

}  // namespace truecut::sim
