// Plane axes, swept angle and points of arcs (path_geometry.hpp).
#include <cmath>
#include <cstdlib>
#include <numbers>

#include "truecut/interp/path_geometry.hpp"

namespace truecut::interp::path_geometry {

PlaneAxes plane_axes(Plane plane) noexcept {
  switch (plane) {
    case Plane::kXZ:
      return {2, 0, 1};
    case Plane::kYZ:
      return {1, 2, 0};
    case Plane::kXY:
      break;
  }
  return {0, 1, 2};
}

double swept_angle_rad(double start_angle_rad, double end_angle_rad, int rotation) noexcept {
  constexpr double kTwoPi = 2 * std::numbers::pi;
  constexpr double kSame = 1e-12;  // directions this close: a full turn
  double sweep = end_angle_rad - start_angle_rad;
  const int extra_turns = (rotation == 0 ? 1 : std::abs(rotation)) - 1;
  if (rotation > 0) {
    while (sweep <= kSame)
      sweep += kTwoPi;
    sweep += kTwoPi * extra_turns;
  } else {
    while (sweep >= -kSame)
      sweep -= kTwoPi;
    sweep -= kTwoPi * extra_turns;
  }
  return sweep;
}

PlaneArc plane_arc(double start_u_mm, double start_v_mm, double end_u_mm, double end_v_mm,
                   double centre_u_mm, double centre_v_mm, int rotation) noexcept {
  const double su = start_u_mm - centre_u_mm, sv = start_v_mm - centre_v_mm;
  const double eu = end_u_mm - centre_u_mm, ev = end_v_mm - centre_v_mm;
  PlaneArc a;
  a.centre_u_mm = centre_u_mm;
  a.centre_v_mm = centre_v_mm;
  a.start_radius_mm = std::hypot(su, sv);
  a.end_radius_mm = std::hypot(eu, ev);
  a.start_angle_rad = std::atan2(sv, su);
  a.sweep_rad = swept_angle_rad(a.start_angle_rad, std::atan2(ev, eu), rotation);
  return a;
}

PlanePoint plane_point_at(const PlaneArc& a, double f) noexcept {
  const double th = a.start_angle_rad + a.sweep_rad * f;
  const double r = a.start_radius_mm + (a.end_radius_mm - a.start_radius_mm) * f;
  return {a.centre_u_mm + r * std::cos(th), a.centre_v_mm + r * std::sin(th)};
}

double plane_length_mm(const PlaneArc& a) noexcept {
  return 0.5 * (a.start_radius_mm + a.end_radius_mm) * std::abs(a.sweep_rad);
}

double helix_length_mm(double radius_mm, double sweep_rad, double axial_mm) noexcept {
  return std::hypot(radius_mm * std::abs(sweep_rad), axial_mm);
}

}  // namespace truecut::interp::path_geometry
