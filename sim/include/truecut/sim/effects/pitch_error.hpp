// pitch_error (ISO 230-1 positioning errors EXX, EYY, EZZ): the table moves
// a little more or less than the screw turns, as a linear scale error plus a
// periodic leadscrew error:
//
//   e(p) = k · (p − p_ref) · 1e-6  +  A · 1e-3 · sin(2π · p / P + φ)     [mm]
//
// p is the axis position at the screw (the encoder side, mm), k the scale
// error in µm/m, A the periodic amplitude in µm, P its period in mm (often
// the screw lead), φ its phase. The true table position is p + e(p); the
// encoder reads p.
#pragma once

#include <cmath>
#include <numbers>

namespace truecut::sim {

struct PitchErrorAxis {
  double scale_um_per_m = 0.0;
  double reference_mm = 0.0;  // where the linear part is zero
  double periodic_amplitude_um = 0.0;
  double periodic_period_mm = 10.0;  // > 0
  double periodic_phase_deg = 0.0;
  bool operator==(const PitchErrorAxis&) const = default;
};

inline double pitch_error_mm(const PitchErrorAxis& e, double pos_mm) noexcept {
  const double linear = e.scale_um_per_m * 1e-6 * (pos_mm - e.reference_mm);
  const double phase = 2.0 * std::numbers::pi * pos_mm / e.periodic_period_mm +
                       e.periodic_phase_deg * (std::numbers::pi / 180.0);
  return linear + e.periodic_amplitude_um * 1e-3 * std::sin(phase);
}

}  // namespace truecut::sim
