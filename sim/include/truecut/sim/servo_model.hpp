// The joint servo: a semi-closed position loop on the motor-side encoder,
// a PI velocity loop driving the joint's inertia against friction, an
// acceleration (force) limit and encoder quantisation. Pure functions on a
// state struct: no allocation, no exceptions, bounded loops.
//
// Per servo period T (the drive samples its encoder at the start of the
// period and holds the velocity reference over it):
//   enc   = round(p / q) · q                            (q: encoder resolution)
//   v_ref = ff1 · (cmd_k − cmd_(k−1)) / T + kv · (cmd_k − enc)
// then, integrated with N = ceil(T / 25 µs) semi-implicit Euler sub-steps:
//   a_drv = clamp(Kp · (v_ref − v) + Ki · ∫(v_ref − v) dt, ±a_max)
//   a     = a_drv − friction   (reversal_spike.hpp: Coulomb + viscous, stick at v = 0)
//   v' = a,  p' = v,  table = play operator(table, p)   (backlash.hpp)
// with Kp = 2π f_v, Ki = Kp / T_n. The integrator stops while the limit
// holds in the direction the error pushes (anti-windup). The sub-step keeps
// Kp·h <= 0.16 for f_v up to 1 kHz, so any period from 125 µs to 1 ms (and
// beyond) is stable and the velocity loop behaves the same; only the
// position loop's sampling follows the period, as in a real drive.
#pragma once

#include <cmath>

#include "truecut/sim/servo_linear_step.hpp"

namespace truecut::sim {

struct ServoParams {
  double kv_per_s = 30.0;
  double ff1 = 0.0;
  double vel_kp_per_s = 251.3;   // 2π · 40 Hz
  double vel_ki_per_s2 = 25133;  // Kp / 0.01 s
  double max_accel = 5000.0;     // unit/s²
  double coulomb_accel = 0.0;    // F_c / inertia, unit/s²
  double viscous_per_s = 0.0;    // B / inertia, 1/s
  double encoder_resolution = 0.0;
  double backlash_play = 0.0;
};

struct ServoState {
  double pos = 0.0;           // motor side, where the encoder sits (unit)
  double vel = 0.0;           // unit/s
  double vel_integral = 0.0;  // ∫(v_ref − v) dt, unit
  double table = 0.0;         // table side of the backlash gap (unit)
  double prev_cmd = 0.0;
};

// The axis starts at rest at `pos` with the gap centred.
ServoState servo_start(double pos) noexcept;

inline double encoder_reading(const ServoParams& p, double pos) noexcept {
  return p.encoder_resolution > 0.0 ? std::round(pos / p.encoder_resolution) * p.encoder_resolution
                                    : pos;
}

int servo_substeps(double period_s) noexcept;

// Advances the state from the start of a period to its end, with `cmd` the
// command of this period. Reads the encoder at the start, as the drive does.
void servo_step(const ServoParams& p, ServoState& s, double cmd, double period_s) noexcept;
// The same, taking the period's sub-steps as one where they are provably
// linear (servo_linear_step.hpp), with the maps kept in `cache`; the state
// differs from the one-by-one sub-steps only by rounding.
void servo_step(const ServoParams& p, ServoState& s, double cmd, double period_s,
                ServoLinearCache& cache) noexcept;

}  // namespace truecut::sim
