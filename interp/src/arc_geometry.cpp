#include "arc_geometry.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "truecut/interp/path_geometry.hpp"

namespace truecut::interp {

namespace {

constexpr double kTiny = 1e-12;

double tolerance(const ArcRequest& r) {
  return r.inch ? 0.0005 : 0.005;
}

// LinuxCNC's allowance for the two radii of a centre-format arc: 2 x 0.001
// inch x sqrt(2) (2 x 0.01 mm x sqrt(2) in G21); beyond 100 times that, or
// beyond it with more than 0.1 % relative difference, the arc is refused.
double center_tolerance(const ArcRequest& r) {
  return 2.0 * (r.inch ? 0.001 : 0.01) * std::numbers::sqrt2;
}

ArcResult radius_form(const ArcRequest& r) {
  if (r.end[0] == r.start[0] && r.end[1] == r.start[1])
    throw ArcDataError{
        "radius-format arc (R) cannot end where it starts: use I/J/K for a full circle", 'r'};
  const double abs_radius = std::fabs(r.radius);
  if (abs_radius < tolerance(r)) throw ArcDataError{"arc radius R is zero or too small", 'r'};
  const double mid0 = (r.end[0] + r.start[0]) / 2.0;
  const double mid1 = (r.end[1] + r.start[1]) / 2.0;
  double half_length = std::hypot(mid0 - r.end[0], mid1 - r.end[1]);
  if (half_length - abs_radius > tolerance(r)) {
    char msg[160];
    std::snprintf(msg, sizeof msg,
                  "arc radius R %.4f is too small to reach the end point (needs at least %.4f)",
                  abs_radius, half_length);
    throw ArcDataError{msg, 'r'};
  }
  if (half_length / abs_radius > 1.0 - kTiny) half_length = abs_radius;
  const double chord = std::atan2(r.end[1] - r.start[1], r.end[0] - r.start[0]);
  // The centre lies to the right of the chord for a short clockwise arc.
  const bool right = (r.clockwise && r.radius > 0) || (!r.clockwise && r.radius < 0);
  const double theta = right ? chord - std::numbers::pi / 2 : chord + std::numbers::pi / 2;
  const double offset = abs_radius * std::cos(std::asin(half_length / abs_radius));
  ArcResult out;
  out.center[0] = mid0 + offset * std::cos(theta);
  out.center[1] = mid1 + offset * std::sin(theta);
  out.rotation = r.clockwise ? -r.turns : r.turns;
  return out;
}

ArcResult center_form(const ArcRequest& r) {
  ArcResult out;
  for (int i = 0; i < 2; ++i)
    out.center[i] = r.absolute_center ? r.center_in[i] : r.start[i] + r.center_in[i];
  const double r1 = std::hypot(out.center[0] - r.start[0], out.center[1] - r.start[1]);
  const double r2 = std::hypot(out.center[0] - r.end[0], out.center[1] - r.end[1]);
  const double tol = tolerance(r);
  if (r1 < tol || r2 < tol)
    throw ArcDataError{"zero-radius arc: the centre is on the start or end point", 'i'};
  const double abs_err = std::fabs(r1 - r2);
  const double rel_err = abs_err / std::max(r1, r2);
  const double allowed = center_tolerance(r);
  if (abs_err > allowed * 100.0 || (rel_err > 0.001 && abs_err > allowed)) {
    char msg[200];
    std::snprintf(msg, sizeof msg,
                  "arc radius mismatch: radius to start %.4f, radius to end %.4f (difference "
                  "%.4g exceeds the tolerance)",
                  r1, r2, abs_err);
    throw ArcDataError{msg, 'i'};
  }
  out.rotation = r.clockwise ? -r.turns : r.turns;
  return out;
}

}  // namespace

ArcResult compute_arc(const ArcRequest& request) {
  return request.radius_form ? radius_form(request) : center_form(request);
}

double arc_length(const ArcRequest& r, const ArcResult& arc, double axis_travel) {
  const path_geometry::PlaneArc a = path_geometry::plane_arc(
      r.start[0], r.start[1], r.end[0], r.end[1], arc.center[0], arc.center[1], arc.rotation);
  return path_geometry::helix_length_mm(a.start_radius_mm, a.sweep_rad, axis_travel);
}

}  // namespace truecut::interp
