// The curve of a NurbsFeed call (G5, G5.1, G5.2 ... G5.3): LinuxCNC's
// rational B-spline with the clamped uniform knot vector, evaluated in the
// plane of its control points (program units, X Y).
#pragma once

#include <array>
#include <vector>

#include "truecut/interp/canon.hpp"

namespace truecut::interp {

using NurbsPoint2 = std::array<double, 2>;

// The parameter runs from 0 to n - k + 2 (n + 1 control points, order k).
double nurbs_parameter_end(const NurbsFeed& nurbs);

// The point at parameter `u` (clamped to the parameter range). The curve
// starts at the first control point and ends at the last. Weights must be
// positive (the interpreter refuses others).
NurbsPoint2 nurbs_point(const NurbsFeed& nurbs, double u);

// The curve as a polyline whose chords stay within `tolerance` (program
// units, > 0) of it: the points after the first control point, the last
// one exactly the last control point. Each knot span starts as 8 chords;
// a chord is halved while a curve point at a quarter, half or three
// quarters of its parameter interval lies farther than `tolerance` from it
// (at most 2^20 chords per span).
std::vector<NurbsPoint2> nurbs_polyline(const NurbsFeed& nurbs, double tolerance);

}  // namespace truecut::interp
