// Machine descriptions and command paths shared by the sim tests.
#pragma once

#include <cmath>
#include <functional>
#include <numbers>
#include <vector>

#include "truecut/sim/machine_model.hpp"

namespace truecut::sim::test {

// All five joints with wide travel and default drives, every effect off.
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
