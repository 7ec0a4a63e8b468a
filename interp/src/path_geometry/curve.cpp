// Lines and helices in x y z: length, points, tangents, sampling
// (path_geometry.hpp).
#include <algorithm>
#include <cmath>

#include "truecut/interp/path_geometry.hpp"

namespace truecut::interp::path_geometry {

namespace {

Point3 unit(const Point3& v) {
  const double n = std::hypot(v[0], v[1], v[2]);
  if (!(n > 0)) return {0, 0, 0};
  return {v[0] / n, v[1] / n, v[2] / n};
}

double fraction_at_length(double s_mm, double length) {
  if (!(length > 0)) return 0.0;
  return std::clamp(s_mm / length, 0.0, 1.0);
}

template <class Curve>
std::vector<Point3> points(const Curve& c, int n) {
  std::vector<Point3> out;
  out.reserve(static_cast<std::size_t>(n) + 1);
  out.push_back(c.start_mm);
  for (int k = 1; k < n; ++k)
    out.push_back(point_at(c, static_cast<double>(k) / n));
  out.push_back(c.end_mm);
  return out;
}

}  // namespace

Helix helix_through(Plane plane, const Point3& start_mm, const Point3& end_mm,
                    double centre_first_mm, double centre_second_mm, int rotation) noexcept {
  Helix h;
  h.axes = plane_axes(plane);
  h.start_mm = start_mm;
  h.end_mm = end_mm;
  h.arc = plane_arc(start_mm[h.axes.first], start_mm[h.axes.second], end_mm[h.axes.first],
                    end_mm[h.axes.second], centre_first_mm, centre_second_mm, rotation);
  return h;
}

double length_mm(const Line& l) noexcept {
  return std::hypot(l.end_mm[0] - l.start_mm[0], l.end_mm[1] - l.start_mm[1],
                    l.end_mm[2] - l.start_mm[2]);
}

double length_mm(const Helix& h) noexcept {
  return std::hypot(plane_length_mm(h.arc), h.end_mm[h.axes.normal] - h.start_mm[h.axes.normal]);
}

Point3 point_at(const Line& l, double f) noexcept {
  return line_point_at(l.start_mm, l.end_mm, f, 3);
}

Point3 point_at(const Helix& h, double f) noexcept {
  return arc_point_at(h.axes, h.arc, h.start_mm, h.end_mm, f, 3);
}

Point3 point_at_length(const Line& l, double s_mm) noexcept {
  return point_at(l, fraction_at_length(s_mm, length_mm(l)));
}

Point3 point_at_length(const Helix& h, double s_mm) noexcept {
  return point_at(h, fraction_at_length(s_mm, length_mm(h)));
}

Point3 tangent_at(const Line& l, double) noexcept {
  return unit(
      {l.end_mm[0] - l.start_mm[0], l.end_mm[1] - l.start_mm[1], l.end_mm[2] - l.start_mm[2]});
}

Point3 tangent_at(const Helix& h, double f) noexcept {
  // d/df of centre + r(f) (cos θ(f), sin θ(f)), θ = θ0 + sweep f.
  const PlaneArc& a = h.arc;
  const double th = a.start_angle_rad + a.sweep_rad * f;
  const double r = a.start_radius_mm + (a.end_radius_mm - a.start_radius_mm) * f;
  const double dr = a.end_radius_mm - a.start_radius_mm;
  Point3 d{};
  d[h.axes.first] = dr * std::cos(th) - r * a.sweep_rad * std::sin(th);
  d[h.axes.second] = dr * std::sin(th) + r * a.sweep_rad * std::cos(th);
  d[h.axes.normal] = h.end_mm[h.axes.normal] - h.start_mm[h.axes.normal];
  return unit(d);
}

int arc_pieces_for_chord(double radius_mm, double sweep_rad, double chord_tolerance_mm) noexcept {
  if (!(radius_mm > chord_tolerance_mm)) return 1;
  const double max_piece_rad = 2.0 * std::acos(1.0 - chord_tolerance_mm / radius_mm);
  const double n = std::ceil(std::fabs(sweep_rad) / max_piece_rad - 1e-9);
  return static_cast<int>(std::clamp(n, 1.0, 1e7));  // as pieces_for_step
}

int pieces_for_step(double length_mm, double max_step_mm) noexcept {
  if (!(max_step_mm > 0)) return 1;
  const double n = std::ceil(length_mm / max_step_mm - 1e-9);
  return static_cast<int>(std::clamp(n, 1.0, 1e7));
}

std::vector<Point3> sample(const Line& l, double max_step_mm) {
  return points(l, pieces_for_step(length_mm(l), max_step_mm));
}

std::vector<Point3> sample(const Helix& h, double chord_tolerance_mm, double max_step_mm) {
  int n = pieces_for_step(length_mm(h), max_step_mm);
  if (chord_tolerance_mm > 0)
    n = std::max(n, arc_pieces_for_chord(std::max(h.arc.start_radius_mm, h.arc.end_radius_mm),
                                         h.arc.sweep_rad, chord_tolerance_mm));
  return points(h, n);
}

}  // namespace truecut::interp::path_geometry
