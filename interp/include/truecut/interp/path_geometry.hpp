// Path geometry of G-code moves: straight lines, G2/G3 arcs and helices in
// any plane (G17 XY, G18 XZ, G19 YZ). One place for the swept angle of an
// arc (with P turns), its length, the point at a fraction or at an arc
// length, the tangent, and how finely to sample it (chord tolerance, largest
// step). Pure functions, no state: the interpreter (inverse-time feed), the
// planner (path pieces), the rewriter (densified tool path) and offline's
// tool-centre placement all use these, so they agree to the last bit.
//
// Conventions (LinuxCNC's canonical ARC_FEED): the two plane coordinates are
// ordered (first, second) = XY: (x, y), XZ: (z, x), YZ: (y, z), and the
// angle is counter-clockwise from `first` towards `second` seen from the
// positive normal axis (z, y, x). `rotation` is ArcFeed::rotation: > 0
// counter-clockwise (G3), < 0 clockwise (G2), |rotation| the number of turns
// (P; 1 for an arc under a turn). Lengths are in the caller's length unit
// (mm everywhere truecut calls these), angles in radians.
#pragma once

#include <array>
#include <vector>

#include "truecut/interp/canon.hpp"

namespace truecut::interp::path_geometry {

// Indices (0 = x, 1 = y, 2 = z) of the plane coordinates and of the normal.
struct PlaneAxes {
  int first = 0, second = 1, normal = 2;
};
PlaneAxes plane_axes(Plane plane) noexcept;

// The signed angle swept from the direction start_angle_rad to
// end_angle_rad (both about the centre) by an arc of the given rotation: in
// (0, 2π] + 2π(|rotation| - 1) counter-clockwise, the negative of that
// clockwise. Directions within 1e-12 rad count as equal: a full turn.
// rotation 0 (no valid ArcFeed has it) counts as -1.
double swept_angle_rad(double start_angle_rad, double end_angle_rad, int rotation) noexcept;

// An arc in plane coordinates (u, v) = (first, second): centre, start and
// end radius (a spiral when they differ: the radius changes linearly with
// the angle), start angle and signed sweep.
struct PlaneArc {
  double centre_u_mm = 0, centre_v_mm = 0;
  double start_radius_mm = 0, end_radius_mm = 0;
  double start_angle_rad = 0, sweep_rad = 0;
};
PlaneArc plane_arc(double start_u_mm, double start_v_mm, double end_u_mm, double end_v_mm,
                   double centre_u_mm, double centre_v_mm, int rotation) noexcept;

struct PlanePoint {
  double u_mm = 0, v_mm = 0;
};
// The point at fraction f of the sweep (f in [0, 1]).
PlanePoint plane_point_at(const PlaneArc& arc, double fraction) noexcept;
// Length in the plane: exact for a circle, the mean radius times the sweep
// for a spiral.
double plane_length_mm(const PlaneArc& arc) noexcept;
// Length of a helix of constant radius: hypot(radius * |sweep|, axial).
double helix_length_mm(double radius_mm, double sweep_rad, double axial_mm) noexcept;

// Moves over any number of coordinates (x y z first, then rotary axes or
// others), for a point type P indexable by int (Axes6, std::array<double, N>).
// Every coordinate goes linearly from start to end with the fraction,
// except, on an arc, the two plane coordinates, which follow the arc.
template <class P>
P line_point_at(const P& start, const P& end, double fraction, int coordinates) noexcept {
  P out{};
  for (int i = 0; i < coordinates; ++i)
    out[i] = start[i] + fraction * (end[i] - start[i]);
  return out;
}
template <class P>
P arc_point_at(const PlaneAxes& axes, const PlaneArc& arc, const P& start, const P& end,
               double fraction, int coordinates) noexcept {
  P out = line_point_at(start, end, fraction, coordinates);
  const PlanePoint q = plane_point_at(arc, fraction);
  out[axes.first] = q.u_mm;
  out[axes.second] = q.v_mm;
  return out;
}

// --- Curves in x y z (mm) -------------------------------------------------

using Point3 = std::array<double, 3>;

struct Line {
  Point3 start_mm{}, end_mm{};
};
// An arc in a plane, a helix when the normal coordinate changes (linearly
// with the angle), a spiral when the end radius differs from the start one.
struct Helix {
  PlaneAxes axes;
  PlaneArc arc;
  Point3 start_mm{}, end_mm{};
};
// From the end points and the centre's two plane coordinates (ArcFeed).
Helix helix_through(Plane plane, const Point3& start_mm, const Point3& end_mm,
                    double centre_first_mm, double centre_second_mm, int rotation) noexcept;

double length_mm(const Line& line) noexcept;
// Exact for a circle or helix; a spiral counts its mean radius.
double length_mm(const Helix& helix) noexcept;

// Fraction t in [0, 1] (the angle is linear in t: constant speed on a helix).
Point3 point_at(const Line& line, double fraction) noexcept;
Point3 point_at(const Helix& helix, double fraction) noexcept;
// At arc length s from the start (clamped to [0, length]).
Point3 point_at_length(const Line& line, double s_mm) noexcept;
Point3 point_at_length(const Helix& helix, double s_mm) noexcept;
// Unit tangent in the direction of travel ({0, 0, 0} for a zero-length move).
Point3 tangent_at(const Line& line, double fraction) noexcept;
Point3 tangent_at(const Helix& helix, double fraction) noexcept;

// --- Sampling ---------------------------------------------------------------

// Pieces of an arc of the given (largest) radius so that no chord's sagitta
// r (1 - cos(sweep / 2n)) exceeds the tolerance; 1 when the radius is not
// larger than the tolerance.
int arc_pieces_for_chord(double radius_mm, double sweep_rad, double chord_tolerance_mm) noexcept;
// Pieces so that none is longer than max_step_mm (at least 1).
int pieces_for_step(double length_mm, double max_step_mm) noexcept;

// Points at fractions k/n, k = 0..n, with n the smallest count that keeps
// every chord within the tolerance (arcs) and every piece within
// max_step_mm. A tolerance or step <= 0 imposes nothing.
std::vector<Point3> sample(const Line& line, double max_step_mm);
std::vector<Point3> sample(const Helix& helix, double chord_tolerance_mm, double max_step_mm);

}  // namespace truecut::interp::path_geometry
