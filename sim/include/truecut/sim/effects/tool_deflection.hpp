// tool_deflection: the cutting force bends the tool, a cantilever of length L
// (the stick-out) clamped in the holder, free at the tip. Only the force
// component across the tool axis bends it (the axial stiffness is ~100×
// higher). With k the bending stiffness at the tip (k = 3EI/L³) and the
// force F⊥ acting at height u_F above the tip (s_F = 1 − u_F/L), the
// deflection along F⊥ at height u (s = 1 − u/L) is the Euler–Bernoulli curve
//
//   w(u) = (F⊥/k) · s²·(3·s_F − s)/2        u >= u_F  (between load and holder)
//   w(u) = w_tip − θ·u                      u <= u_F  (below the load: straight)
//   w_tip = (F⊥/k) · s_F²·(3 − s_F)/2       = F⊥/k for a load at the tip
//   θ     = (F⊥/k) · 1.5·s_F² / L           slope (rad) of the straight part
//
// The true pose moves its TCP by w_tip along F⊥ and tilts its axis by θ
// towards −F⊥ (the tip leans out, the holder stays): a wall cut with the
// tool's side comes out tapered. tip + axis reproduce the curve exactly
// below the load point; above it the straight line falls short by
// (F⊥/k)·((u − u_F)/L)³/2. Equations and figures: docs/machine-model.md.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <optional>

namespace truecut::sim {

struct ToolDeflectionParams {
  double stiffness_n_per_um = 1.0;    // k at the tip, > 0
  std::optional<double> stickout_mm;  // L, > 0; absent: the true tool length
  bool operator==(const ToolDeflectionParams&) const = default;
};

// The tool's deflection for one force: the straight lower part as a tip
// shift and a tilt, plus what is needed to evaluate the curve anywhere.
struct ToolBend {
  Eigen::Vector3d tip_mm = Eigen::Vector3d::Zero();     // w_tip along F⊥
  Eigen::Vector3d direction = Eigen::Vector3d::Zero();  // unit F⊥ (zero: no bending)
  double slope_rad = 0.0;                               // θ
  double load_height_mm = 0.0;                          // u_F, clamped to [0, L]
  double compliance_mm = 0.0;                           // |F⊥|/k
  double stickout_mm = 0.0;                             // L
};

// force_n: on the tool; axis: unit, tip → spindle; load_height_mm: u_F
// (clamped to [0, L]). No bending without a force across the axis or with a
// stiffness or stick-out that is not > 0. Pure, no allocation.
inline ToolBend tool_bend(double stiffness_n_per_um, double stickout_mm,
                          const Eigen::Vector3d& force_n, const Eigen::Vector3d& axis,
                          double load_height_mm) noexcept {
  ToolBend b;
  b.stickout_mm = stickout_mm;
  b.load_height_mm = std::clamp(load_height_mm, 0.0, std::max(stickout_mm, 0.0));
  const Eigen::Vector3d across = force_n - axis * axis.dot(force_n);
  const double f = across.norm();
  if (!(f > 0.0 && stiffness_n_per_um > 0.0 && stickout_mm > 0.0)) return b;
  b.direction = across / f;
  b.compliance_mm = f / stiffness_n_per_um * 1e-3;
  const double s_f = 1.0 - b.load_height_mm / stickout_mm;
  b.tip_mm = b.direction * (b.compliance_mm * s_f * s_f * (3.0 - s_f) * 0.5);
  b.slope_rad = b.compliance_mm * 1.5 * s_f * s_f / stickout_mm;
  return b;
}

// The exact deflection (mm, along ToolBend::direction) at height u above the
// tip, 0 at and above the holder (u >= L).
inline double tool_bend_at(const ToolBend& b, double height_mm) noexcept {
  if (!(b.compliance_mm > 0.0)) return 0.0;
  const double u = std::clamp(height_mm, 0.0, b.stickout_mm);
  if (u <= b.load_height_mm) return b.tip_mm.norm() - b.slope_rad * u;
  const double s = 1.0 - u / b.stickout_mm;
  const double s_f = 1.0 - b.load_height_mm / b.stickout_mm;
  return b.compliance_mm * s * s * (3.0 * s_f - s) * 0.5;
}

}  // namespace truecut::sim
