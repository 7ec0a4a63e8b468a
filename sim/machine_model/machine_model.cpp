#include "truecut/sim/machine_model.hpp"

#include <cmath>
#include <numbers>

namespace truecut::sim {

namespace {

// Force (N) per kg → mm/s²; torque (N·m) per kg·m² → deg/s².
double accel_per_force_over_inertia(int joint) {
  return joint_kind(joint) == JointKind::Linear ? 1000.0 : 180.0 / std::numbers::pi;
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
  if (!st.started) {
    for (int j = 0; j < kJointCount; ++j)
      st.joints[j] = servo_start(cmd[j]);
    st.started = true;
  }

  for (int j = 0; j < kJointCount; ++j) {
    ServoState& s = st.joints[j];
    const ServoParams& sp = servo_[j];
    const JointParams& jp = params_.joints[j];
    if (!(cmd[j] >= jp.min && cmd[j] <= jp.max)) st.limit_fault = true;

    if (dynamic(j)) {
      const double enc = encoder_reading(sp, s.pos);
      out.pos_act[j] = enc;
      out.f_error[j] = cmd[j] - enc;
      out.vel_act[j] = s.vel;
    } else {
      // Ideal drive: the motor is where it is told, at every instant.
      s.vel = (cmd[j] - s.prev_cmd) / period_s;
      s.pos = cmd[j];
      s.prev_cmd = cmd[j];
      s.table = sp.backlash_play > 0.0 ? backlash_table_position(s.table, s.pos, sp.backlash_play)
                                       : s.pos;
      out.pos_act[j] = cmd[j];
      out.f_error[j] = 0.0;
      out.vel_act[j] = s.vel;
    }

    double pos_true = s.table;
    if (const auto* e = fx.pitch_error.active(j)) pos_true += pitch_error_mm(*e, s.pos);
    if (fx.thermal_drift.active(j)) pos_true += st.thermal_mm[j];
    out.pos_true[j] = pos_true;
  }

  out.xyz_true = apply_geometric_errors(fx.squareness.active(), fx.straightness.active(),
                                        {out.pos_true[kX], out.pos_true[kY], out.pos_true[kZ]});
  const rt::ToolPose pose =
      true_tool_pose(kinematics_, out.xyz_true, out.pos_true[kA], out.pos_true[kC]);
  out.tcp_true = {pose.tcp_mm.x(), pose.tcp_mm.y(), pose.tcp_mm.z()};
  out.tool_axis_true = {pose.axis.x(), pose.axis.y(), pose.axis.z()};

  // Advance to the end of the period.
  for (int j = 0; j < kJointCount; ++j) {
    if (dynamic(j)) servo_step(servo_[j], st.joints[j], cmd[j], period_s);
    if (const auto* e = fx.thermal_drift.active(j))
      st.thermal_mm[j] = thermal_drift_step(*e, st.thermal_mm[j],
                                            thermal_drive(*e, st.spindle_power_kw), period_s);
  }
  ++st.cycles;
  out.fault = st.fault;
  out.limit_fault = st.limit_fault;
}

}  // namespace truecut::sim
