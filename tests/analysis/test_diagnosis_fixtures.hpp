// Recordings generated with the simulator for the diagnosis tests: a
// commanded X/Y path with reversals, constant velocity, accelerations and
// standstill, run through a "true" machine, with noise on what is recorded.
#pragma once

#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "../sim/machine_fixtures.hpp"
#include "truecut/analysis/diagnosis/diagnosis.hpp"
#include "truecut/analysis/recording.hpp"

namespace truecut::analysis::test {
using namespace truecut::sim;
using namespace truecut::sim::test;

// One joint's commanded path: trapezoidal moves through `targets` at the
// given feeds, with a dwell after each move.
class MovePath {
 public:
  struct Move {
    double to, feed;
  };
  MovePath(double start, std::vector<Move> moves, double accel, double dwell_s)
      : start_(start), moves_(std::move(moves)), accel_(accel), dwell_(dwell_s) {}

  double at(double t) const {
    double p = start_;
    for (const auto& m : moves_) {
      const double d = std::abs(m.to - p), s = m.to > p ? 1 : -1;
      double ta = m.feed / accel_, vpk = m.feed, tc;
      if (vpk * ta > d) {
        ta = std::sqrt(d / accel_);
        vpk = accel_ * ta;
        tc = 0;
      } else {
        tc = (d - vpk * ta) / vpk;
      }
      const double T = 2 * ta + tc;
      if (t < T) {
        double x;
        if (t < ta)
          x = 0.5 * accel_ * t * t;
        else if (t < ta + tc)
          x = 0.5 * accel_ * ta * ta + vpk * (t - ta);
        else {
          const double u = T - t;
          x = d - 0.5 * accel_ * u * u;
        }
        return p + s * x;
      }
      t -= T;
      p = m.to;
      if (t < dwell_) return p;
      t -= dwell_;
    }
    return p;
  }

 private:
  double start_;
  std::vector<Move> moves_;
  double accel_, dwell_;
};

struct RecordingSpec {
  double period_s = 1e-3;
  double duration_s = 12.0;
  double noise_mm = 1e-3;      // on every recorded target
  bool meas = true;            // record <j>_meas (true position) besides <j>_act
  double logging_delay_s = 0;  // the recorded targets lag the commands by this
  unsigned seed = 1;
  int record_every = 1;  // keep every n-th servo period (a recorder slower than the servo)
};

inline MovePath default_x_path(int variant = 0) {
  if (variant == 1)
    return MovePath(20,
                    {{70, 25}, {5, 12}, {55, 30}, {15, 8}, {90, 20}, {30, 15}, {75, 25}, {0, 18}},
                    400, 0.3);
  return MovePath(0, {{60, 20}, {10, 10}, {80, 30}, {25, 15}, {90, 8}, {5, 25}, {50, 12}, {20, 30}},
                  400, 0.3);
}
inline MovePath default_y_path(int variant = 0) {
  if (variant == 1)
    return MovePath(10, {{60, 15}, {20, 25}, {70, 10}, {0, 20}, {45, 30}, {15, 12}}, 300, 0.4);
  return MovePath(0, {{40, 15}, {80, 25}, {10, 20}, {65, 10}, {30, 30}, {75, 15}}, 300, 0.4);
}

// Runs the true machine on the X/Y path and writes what a recorder sees.
inline Recording make_recording(const MachineParams& truth, const RecordingSpec& spec,
                                int variant = 0) {
  const MovePath px = default_x_path(variant), py = default_y_path(variant);
  const int n = int(std::lround(spec.duration_s / spec.period_s));
  const int lag = int(std::lround(spec.logging_delay_s / spec.period_s));
  MachineModel model(truth);
  MachineState state;
  std::vector<MachineOutputs> outs;
  std::vector<MachineInputs> ins;
  for (int k = 0; k < n + lag; ++k) {
    MachineInputs in;
    const double t = k * spec.period_s;
    in.pos_cmd[kX] = px.at(t);
    in.pos_cmd[kY] = py.at(t);
    MachineOutputs out;
    model.step(state, in, spec.period_s, out);
    ins.push_back(in);
    outs.push_back(out);
  }
  std::mt19937_64 rng(spec.seed);
  std::normal_distribution<double> unit_noise(0.0, 1.0);
  auto noise = [&](std::mt19937_64& g) { return spec.noise_mm * unit_noise(g); };
  Recording rec;
  rec.file = "simulated.csv";
  for (const char* c : {"x_cmd", "y_cmd", "x_act", "y_act"})
    rec.channels[c];
  if (spec.meas) rec.channels["x_meas"], rec.channels["y_meas"];
  for (int k = 0; k < n; k += spec.record_every) {
    // The target row k holds the value of cycle k − lag.
    const int src = std::max(0, k - lag);
    rec.t_s.push_back(k * spec.period_s);
    rec.channels["x_cmd"].push_back(ins[k].pos_cmd[kX]);
    rec.channels["y_cmd"].push_back(ins[k].pos_cmd[kY]);
    rec.channels["x_act"].push_back(outs[src].pos_act[kX] + (spec.meas ? 0 : noise(rng)));
    rec.channels["y_act"].push_back(outs[src].pos_act[kY] + (spec.meas ? 0 : noise(rng)));
    if (spec.meas) {
      rec.channels["x_meas"].push_back(outs[src].xyz_true[kX] + noise(rng));
      rec.channels["y_meas"].push_back(outs[src].xyz_true[kY] + noise(rng));
    }
  }
  return rec;
}

// X and Y present with wide travel; Z present (required by the format) but idle.
inline MachineDescription xy_machine() {
  MachineDescription d;
  d.name = "test mill";
  d.machine = ideal_params();
  d.machine.joints[kA].present = false;
  d.machine.joints[kC].present = false;
  return d;
}

inline constexpr double kTcpNoiseMm = 1e-3;  // σ of the measured TCP

// A trunnion machine (trunnion_params) with a known servo lag on X and Y.
inline MachineDescription trunnion_with_servo() {
  MachineDescription d;
  d.name = "trunnion";
  d.machine = trunnion_params();
  enable_servo_lag(d.machine, kX, 40.0, 0.9);
  enable_servo_lag(d.machine, kY, 35.0, 0.8);
  return d;
}

// X, Y, Z sweep, A tilts 0…90° and back every 5 s, C turns once every 8 s;
// 20 s at 200 Hz (the model stepped at 1 kHz).
inline Recording five_axis_recording(const MachineParams& truth, unsigned seed,
                                     double tcp_noise_mm = kTcpNoiseMm,
                                     double encoder_noise_mm = 0.2e-3) {
  MachineModel model(truth);
  MachineState state;
  std::mt19937_64 rng(seed);
  // Unit draws scaled (σ = 0 is allowed), one distribution per channel kind
  // as before, so the default recordings keep their noise sequence.
  std::normal_distribution<double> unit_tcp(0.0, 1.0), unit_encoder(0.0, 1.0);
  auto noise = [&](std::mt19937_64& g) { return tcp_noise_mm * unit_tcp(g); };
  auto encoder_noise = [&](std::mt19937_64& g) { return encoder_noise_mm * unit_encoder(g); };
  Recording rec;
  rec.file = "five_axis.csv";
  const double dt = 1e-3;
  // The machine is commanded every 1 ms along smooth curves and recorded
  // every 5 ms; the re-simulation reads the command back between the
  // samples (cubic), which is exact to far below the encoder noise here.
  auto command = [](double t) {
    std::array<double, kJointCount> q{};
    q[kX] = 30 * std::sin(2 * std::numbers::pi * t / 7);
    q[kY] = 20 * std::sin(2 * std::numbers::pi * t / 11 + 1);
    q[kZ] = -10 + 10 * std::sin(2 * std::numbers::pi * t / 13);
    q[kA] = 45 - 45 * std::cos(2 * std::numbers::pi * t / 5);
    q[kC] = 45 * t;
    return q;
  };
  for (int k = 0; k < 20000; ++k) {
    const double t = k * dt;
    const auto q = command(t);
    MachineInputs in;
    for (int j = 0; j < kJointCount; ++j)
      in.pos_cmd[j] = q[j];
    MachineOutputs out;
    model.step(state, in, dt, out);
    if (k % 5 != 0) continue;
    rec.t_s.push_back(t);
    for (int j = 0; j < kJointCount; ++j) {
      const std::string name(kJointNames[j]);
      rec.channels[name + "_cmd"].push_back(in.pos_cmd[j]);
      rec.channels[name + "_act"].push_back(out.pos_act[j] + encoder_noise(rng));
    }
    for (int c = 0; c < 3; ++c)
      rec.channels[std::string("tcp_true_") + "xyz"[c]].push_back(out.tcp_true[c] + noise(rng));
  }
  return rec;
}

}  // namespace truecut::analysis::test
