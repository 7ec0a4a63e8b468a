// workpiece_deflection: a slender part (the implant shaft) is a cantilever
// clamped at a plane through the clamp point P, normal to its axis a (unit,
// pointing to the free end; given as any non-zero vector), in the workpiece
// frame. The force on the tool
// F pushes the part the other way; at the contact point c, at height
// h = (c − P)·a above the clamp, a point load bends it by
//
//   δ = F⊥ / k_ref · (h / L_ref)³        h > 0;  0 at and below the clamp
//   F⊥ = F − (F·a)·a                      only the part across the axis bends it
//
// (k_ref: stiffness at L_ref above the clamp, 3EI/L_ref³). The part moves by
// −δ, so relative to the (undeformed) workpiece frame the tool moves by +δ:
// the true TCP gets +δ. The local rotation of the part at the contact
// (1.5·δ/h) is not applied to the tool axis. Equations and figures:
// docs/machine-model.md.
#pragma once

#include <Eigen/Core>
#include <array>

namespace truecut::sim {

struct WorkpieceDeflectionParams {
  double stiffness_n_per_um = 1.0;            // k_ref, > 0
  double reference_length_mm = 10.0;          // L_ref, > 0
  std::array<double, 3> clamp_point_mm{};     // P, workpiece frame
  std::array<double, 3> axis{0.0, 0.0, 1.0};  // a: its direction (any length > 0)
  bool operator==(const WorkpieceDeflectionParams&) const = default;
};

// δ in mm (workpiece frame) for the force on the tool at the contact point;
// zero when the stiffness or the reference length is not > 0 or the axis is
// zero. Pure, no allocation.
inline Eigen::Vector3d workpiece_deflection_mm(const WorkpieceDeflectionParams& p,
                                               const Eigen::Vector3d& force_n,
                                               const Eigen::Vector3d& contact_mm) noexcept {
  const Eigen::Vector3d a = Eigen::Vector3d(p.axis[0], p.axis[1], p.axis[2]).normalized();
  const Eigen::Vector3d clamp(p.clamp_point_mm[0], p.clamp_point_mm[1], p.clamp_point_mm[2]);
  const double h = (contact_mm - clamp).dot(a);
  if (!(h > 0.0 && p.stiffness_n_per_um > 0.0 && p.reference_length_mm > 0.0))
    return Eigen::Vector3d::Zero();
  const double r = h / p.reference_length_mm;
  return (force_n - a * a.dot(force_n)) * (r * r * r / p.stiffness_n_per_um * 1e-3);
}

}  // namespace truecut::sim
