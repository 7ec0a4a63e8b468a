// thermal_drift: first-order thermal growth δ of an axis, added to its true
// position:
//
//   dδ/dt = (g · u(t) − δ) / τ
//
// driven by time (u = 1: a warm-up from δ = 0 at the start towards g) or by
// spindle power (u = P / P_ref). Integrated exactly for u held over a servo
// period:  δ ← δ + (g·u − δ) · (1 − e^(−T/τ)).
#pragma once

#include <cmath>

namespace truecut::sim {

enum class ThermalDriver { kTime, kSpindlePower };

struct ThermalDriftAxis {
  double gain_mm = 0.0;  // g: steady-state growth at u = 1
  double tau_s = 600.0;  // τ > 0
  ThermalDriver driver = ThermalDriver::kTime;
  double reference_power_kw = 10.0;  // P_ref > 0, used with the spindle-power driver
  bool operator==(const ThermalDriftAxis&) const = default;
};

inline double thermal_drive(const ThermalDriftAxis& e, double spindle_power_kw) noexcept {
  return e.driver == ThermalDriver::kTime ? 1.0 : spindle_power_kw / e.reference_power_kw;
}

inline double thermal_drift_step(const ThermalDriftAxis& e, double delta_mm, double drive,
                                 double period_s) noexcept {
  return delta_mm + (e.gain_mm * drive - delta_mm) * -std::expm1(-period_s / e.tau_s);
}

}  // namespace truecut::sim
