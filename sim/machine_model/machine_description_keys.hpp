// JSON key names that depend on the joint's unit (shared by reader and writer).
#pragma once

#include <array>
#include <string>

#include "truecut/sim/joints.hpp"

namespace truecut::sim::detail {

// vel_bandwidth_hz, vel_integral_time_s, inertia, max_accel, encoder_resolution
inline std::array<std::string, 5> drive_keys(int joint) {
  if (joint_kind(joint) == JointKind::kLinear)
    return {"vel_bandwidth_hz", "vel_integral_time_s", "mass_kg", "max_accel_mm_per_s2",
            "encoder_resolution_mm"};
  return {"vel_bandwidth_hz", "vel_integral_time_s", "inertia_kg_m2", "max_accel_deg_per_s2",
          "encoder_resolution_deg"};
}

// Coulomb, viscous
inline std::array<std::string, 2> friction_keys(int joint) {
  if (joint_kind(joint) == JointKind::kLinear) return {"coulomb_n", "viscous_n_s_per_mm"};
  return {"coulomb_nm", "viscous_nm_s_per_deg"};
}

}  // namespace truecut::sim::detail
