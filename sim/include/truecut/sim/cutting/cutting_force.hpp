// Spindle power and cutting force from the removal rate (specific cutting
// force model). See docs/cutting.md, "Cutting force".
#pragma once

#include <Eigen/Core>

#include "truecut/sim/cutting/dexel_model.hpp"

namespace truecut::sim::cutting {

struct ForceModel {
  double kc_n_per_mm2 = 1800;  // specific cutting force (steel / Ti-6Al-4V finishing)
  double kr = 0.4;             // radial (passive) force / tangential force
};

struct CuttingLoad {
  double mrr_mm3_per_s = 0;
  double power_w = 0;                                 // P = kc · MRR
  double tangential_force_n = 0;                      // Fc = P / vc
  Eigen::Vector3d force_n = Eigen::Vector3d::Zero();  // Fr = kr·Fc along the normal, on the tool
  double cutting_speed_mm_per_s = 0;                  // vc = π · D · n / 60
};

// Removal of one step of dt_s seconds with a cutter of radius_mm at
// spindle_rpm. No spindle (|rpm| < 1e-9), dt ≤ 0 or non-finite input: zero
// force (and zero power when dt ≤ 0).
CuttingLoad cutting_load(const Engagement& e, double dt_s, double radius_mm, double spindle_rpm,
                         const ForceModel& model) noexcept;

}  // namespace truecut::sim::cutting
