// Geometric component errors of the linear axes (ISO 230-1), applied to the
// table-side positions (x, y, z) of the three slides, each already carrying
// its joint-level errors. All are first-order small: they add.
//
// squareness (µrad; positive when the angle between the positive directions
// of the two axes is smaller than 90°; 1 arcsec = 4.848 µrad):
//   xy (E_C0Y, Y to X):  x += γ_xy · y
//   yz (E_A0Z, Z to Y):  y += γ_yz · z
//   zx (E_B0Z, Z to X):  x += γ_zx · z
// On a circle of radius R in XY this gives the radial error
// (R·γ_xy/2) · sin 2θ: the 2θ lobe with its long axis at 45°/225°.
//
// straightness (EYX, EZX, EXY, EZY, EXZ, EYZ: E_<direction><moving axis>),
// the bow of an axis' path, as a polynomial without constant and linear
// terms (those are offsets and squareness):
//   e(u) = c2 · s² + c3 · s³   [µm],  s = (u − u_ref) / 1000   [m]
// e.g. EYX adds e(x) to y.
#pragma once

#include <array>
#include <optional>

namespace truecut::sim {

struct SquarenessParams {
  double xy_urad = 0.0;
  double yz_urad = 0.0;
  double zx_urad = 0.0;
  bool operator==(const SquarenessParams&) const = default;
};

struct StraightnessComponent {
  double quadratic_um_per_m2 = 0.0;
  double cubic_um_per_m3 = 0.0;
  double reference_mm = 0.0;
  bool operator==(const StraightnessComponent&) const = default;
};

enum StraightnessIndex : int { kEYX = 0, kEZX, kEXY, kEZY, kEXZ, kEYZ, kStraightnessCount };
inline constexpr std::array<const char*, kStraightnessCount> kStraightnessNames = {
    "eyx", "ezx", "exy", "ezy", "exz", "eyz"};
// For each component: the moving axis (argument) and the direction it errs in.
inline constexpr std::array<int, kStraightnessCount> kStraightnessMoving = {0, 0, 1, 1, 2, 2};
inline constexpr std::array<int, kStraightnessCount> kStraightnessDirection = {1, 2, 0, 2, 0, 1};

struct StraightnessParams {
  std::array<std::optional<StraightnessComponent>, kStraightnessCount> components;
  bool operator==(const StraightnessParams&) const = default;
};

inline double straightness_mm(const StraightnessComponent& c, double pos_mm) noexcept {
  const double s = (pos_mm - c.reference_mm) * 1e-3;
  return (c.quadratic_um_per_m2 + c.cubic_um_per_m3 * s) * s * s * 1e-3;
}

// `squareness` / `straightness` may be null (effect off).
inline std::array<double, 3> apply_geometric_errors(const SquarenessParams* squareness,
                                                    const StraightnessParams* straightness,
                                                    const std::array<double, 3>& xyz) noexcept {
  std::array<double, 3> out = xyz;
  if (squareness) {
    out[0] += squareness->xy_urad * 1e-6 * xyz[1] + squareness->zx_urad * 1e-6 * xyz[2];
    out[1] += squareness->yz_urad * 1e-6 * xyz[2];
  }
  if (straightness) {
    for (int i = 0; i < kStraightnessCount; ++i)
      if (const auto& c = straightness->components[i])
        out[kStraightnessDirection[i]] += straightness_mm(*c, xyz[kStraightnessMoving[i]]);
  }
  return out;
}

}  // namespace truecut::sim
