// Machine descriptions and command paths shared by the sim tests.
#pragma once

#include <cmath>
#include <cstring>
#include <functional>
#include <numbers>
#include <vector>

#include "truecut/sim/machine_model.hpp"

namespace truecut::sim::test {

// All five joints with wide travel and default drives, every effect off.
// Bit-for-bit equality of every output field (not of the struct's padding).
inline bool bitwise_equal(const MachineOutputs& a, const MachineOutputs& b) {
  auto same = [](const auto& x, const auto& y) {
    return std::memcmp(x.data(), y.data(), sizeof x) == 0;
  };
  return same(a.pos_act, b.pos_act) && same(a.pos_true, b.pos_true) && same(a.vel_act, b.vel_act) &&
         same(a.f_error, b.f_error) && same(a.xyz_true, b.xyz_true) &&
         same(a.tcp_true, b.tcp_true) && same(a.tool_axis_true, b.tool_axis_true) &&
         same(a.tool_deflection_mm, b.tool_deflection_mm) &&
         same(a.workpiece_deflection_mm, b.workpiece_deflection_mm) && a.fault == b.fault &&
         a.limit_fault == b.limit_fault;
}

inline MachineParams ideal_params() {
  MachineParams m;
  for (int j = 0; j < kJointCount; ++j) {
    m.joints[j].present = true;
    m.joints[j].min = -1000.0;
    m.joints[j].max = 1000.0;
    m.joints[j].drive = default_drive(j);
    m.joints[j].drive.encoder_resolution = 0.0;
  }
  return m;
}

// ideal_params() with the pivots of a trunnion table: C axis at (120, -40)
// with the table top at z = -250, the A axis 30 mm behind it and 60 mm
// above; an 80 mm tool.
inline MachineParams trunnion_params(bool conventional_directions = false) {
  MachineParams m = ideal_params();
  KinematicsParams& k = m.kinematics;
  k.ac.x_rot_point_mm = 120.0;
  k.ac.y_rot_point_mm = -40.0;
  k.ac.z_rot_point_mm = -250.0;
  k.ac.y_offset_mm = 30.0;
  k.ac.z_offset_mm = 60.0;
  k.ac.conventional_directions = conventional_directions;
  k.tool = NominalTool{80.0, 5.0, 0.0};
  return m;
}

inline void enable_servo_lag(MachineParams& m, int joint, double kv_per_s, double ff1 = 0.0) {
  m.effects.servo_lag.enabled = true;
  m.effects.servo_lag.axes[joint] = ServoLagAxis{kv_per_s, ff1};
}

struct Trace {
  std::vector<double> t;
  std::vector<MachineInputs> in;
  std::vector<MachineOutputs> out;
};

// Runs `cycles` servo periods with the commands `path(t)` gives.
inline Trace run(const MachineParams& params, double period_s, int cycles,
                 const std::function<MachineInputs(double)>& path) {
  MachineModel model(params);
  MachineState state;
  Trace tr;
  for (int k = 0; k < cycles; ++k) {
    const double t = k * period_s;
    MachineInputs in = path(t);
    MachineOutputs out;
    model.step(state, in, period_s, out);
    tr.t.push_back(t);
    tr.in.push_back(in);
    tr.out.push_back(out);
  }
  return tr;
}

inline MachineInputs on_x(double x) {
  MachineInputs in;
  in.pos_cmd[kX] = x;
  return in;
}

}  // namespace truecut::sim::test
