// An independent planted-recording generator for the diagnosis tests
// (issue 18, points 3 and 4): recordings of an X/Y/Z machine whose physics
// is written here from the textbook formulas, with its own integration and
// its own command paths, without calling anything in sim/ or analysis/ to
// compute an effect. Only the recording's file format is shared (the CSV of
// docs/formats.md, read back with analysis::read_recording).
//
// Per axis j (mm, s):
//   command c(t)          ISO 230-2 stepping with over-travel, circles or a
//                         3-axis contour (cycloidal moves, smooth ramps)
//   motor p(t)            = c(t) without a servo; with one: a position loop
//                         sampled every servo period T,
//                           v_ref = ff1 · (c_k − c_{k−1}) / T + Kv · (c_k − enc_k)
//                         driving a PI velocity loop on the axis' mass with
//                         Coulomb friction (stick when the drive force is
//                         below F_c), integrated in sub-steps of T / 200
//   encoder enc           = p quantised to the encoder resolution (`<j>_act`)
//   table q               lost motion b between motor and table:
//                         q ← min(max(q, p − b/2), p + b/2)
//   true position         q + pitch(p) + thermal(t),
//                           pitch(p)   = k·(p − p_ref)·1e-6 + A·1e-3·sin(2πp/P + φ)
//                           thermal(t) = g · (1 − exp(−t / τ))   (cold start at t = 0,
//                                        whether the axis moves or not)
//   measured (`<j>_meas`) x += γ_xy·y + γ_zx·z, y += γ_yz·z (µrad), plus
//                         Gaussian noise of σ
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <vector>

namespace truecut::test::planted {

struct Axis {
  // Servo: P position loop with velocity feed-forward around a PI velocity
  // loop. Off: the motor follows the command exactly.
  bool servo = false;
  double kv_per_s = 0.0, ff1 = 0.0;
  double vel_bandwidth_hz = 40.0, vel_integral_time_s = 0.01;
  double mass_kg = 500.0, max_accel = 5000.0, encoder_resolution = 1e-4;
  double coulomb_n = 0.0;  // friction (needs the servo)
  double backlash_mm = 0.0;
  double pitch_scale_um_per_m = 0.0, pitch_reference_mm = 0.0;
  double pitch_amplitude_um = 0.0, pitch_period_mm = 10.0, pitch_phase_deg = 0.0;
  double thermal_gain_mm = 0.0, thermal_tau_s = 1.0;
};

struct Plant {
  std::array<Axis, 3> axes;  // x, y, z
  double xy_urad = 0.0, yz_urad = 0.0, zx_urad = 0.0;
};

enum class PathKind {
  kIso230X,   // ISO 230-2 stepping of X (5 targets, over-travel, dwells); Y, Z stand
  kCircleXY,  // circles in XY, counter-clockwise then clockwise; Z stands
  kContour3,  // X, Y, Z on incommensurate sines from standstill
};

struct Spec {
  PathKind path = PathKind::kIso230X;
  double period_s = 1e-3;  // recording and servo period
  double noise_mm = 1e-3;  // σ on every measured position
  double act_noise_mm = 0.0;
  int iso_cycles = 2;                             // bidirectional ISO 230-2 cycles (1 or 2)
  double circle_turns = 1.5;                      // turns in each direction
  double circle_radius_mm = 20.0;                 // at 40 mm/s whatever the radius
  bool meas = true;                               // record <j>_meas
  std::array<bool, 3> record{true, true, false};  // axes written to the file
  unsigned seed = 1;
};

struct Trace {
  std::vector<double> t;
  std::array<std::vector<double>, 3> cmd, act, meas;
};

// The commanded position of the three axes at t, and the path's duration.
std::array<double, 3> command(const Spec& spec, double t);
double duration_s(const Spec& spec);

Trace generate(const Plant& plant, const Spec& spec);

// Writes the trace as a recording CSV (t, <j>_cmd, <j>_act[, <j>_meas] for
// the recorded axes).
void write_csv(const std::filesystem::path& file, const Trace& trace, const Spec& spec);

}  // namespace truecut::test::planted
