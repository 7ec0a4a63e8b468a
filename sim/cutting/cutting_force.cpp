// Specific-cutting-force model: P = kc·MRR, Fc = P/vc, Fr = kr·Fc.
#include "truecut/sim/cutting/cutting_force.hpp"

#include <cmath>
#include <numbers>

namespace truecut::sim::cutting {

CuttingLoad cutting_load(const Engagement& e, double dt_s, double radius_mm, double spindle_rpm,
                         const ForceModel& model) noexcept {
  CuttingLoad load;
  if (!(dt_s > 0) || !std::isfinite(dt_s) || !std::isfinite(e.removed_mm3)) return load;
  load.mrr_mm3_per_s = e.removed_mm3 / dt_s;
  // N/mm² · mm³/s = N·mm/s = 1e-3 W.
  load.power_w = model.kc_n_per_mm2 * load.mrr_mm3_per_s * 1e-3;
  if (!std::isfinite(spindle_rpm) || std::abs(spindle_rpm) < 1e-9 || !(radius_mm > 0)) return load;
  load.cutting_speed_mm_per_s = std::numbers::pi * 2 * radius_mm * std::abs(spindle_rpm) / 60.0;
  load.tangential_force_n = load.power_w * 1e3 / load.cutting_speed_mm_per_s;  // N·mm/s ÷ mm/s
  load.force_n = model.kr * load.tangential_force_n * e.normal;
  return load;
}

}  // namespace truecut::sim::cutting
