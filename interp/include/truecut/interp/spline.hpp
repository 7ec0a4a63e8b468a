// Sinumerik BSPLINE / CSPLINE over programmed points, with node insertion
// that keeps the contour error inside the CAM tolerance (after Msaddek,
// Baili, Bouaziz, Dessein, IJAMT 97, 2018).
//
// - BSPLINE: the points are the control points of a uniform cubic B-spline
//   that starts and ends at the first and last point. Around each interior
//   control point with a turn of angle β between the adjacent polyline legs,
//   two nodes are inserted on the legs at d2 = 2·Er/sin β (Er = tolerance),
//   which pulls the curve to within the tolerance of the corner.
// - CSPLINE: a natural cubic spline through the points (chord-length
//   parameters). Nodes are inserted at constant length ℓ along every leg;
//   ℓ shrinks until the error is inside the tolerance.
//
// The contour error Er is the largest distance from the spline to the
// programmed polyline (sampled 32 times per span).
#pragma once

#include <vector>

#include "truecut/interp/canon.hpp"
#include "truecut/interp/plan_segment.hpp"

namespace truecut::interp {

// One cubic span, P(t) = c0 + c1 t + c2 t^2 + c3 t^3 for t in [0, 1].
struct CubicSpan {
  Vec5 c0{}, c1{}, c2{}, c3{};
};

struct SplineFit {
  std::vector<Vec5> nodes;  // control points (B) or interpolated points (C) after insertion
  std::vector<CubicSpan> spans;
  double error_mm = 0;  // Er of these spans against the programmed polyline
};

struct SplineReport {
  SplineMode mode = SplineMode::kNone;
  int line = 0;    // program line of the first spline point
  int points = 0;  // programmed points, including the start point
  int nodes_inserted = 0;
  double tolerance_mm = 0;
  double error_before_mm = 0;  // Er of the spline over the programmed points alone
  double error_after_mm = 0;   // Er after node insertion
  bool within_tolerance() const { return error_after_mm <= tolerance_mm; }
};

// Spans over `points` as programmed (no insertion).
SplineFit fit_spline(SplineMode mode, const std::vector<Vec5>& points);
// With node insertion so that Er <= tolerance_mm (where reachable).
SplineFit fit_spline_within(SplineMode mode, const std::vector<Vec5>& points, double tolerance_mm,
                            SplineReport* report = nullptr);
// Largest distance from the spans to the polyline through `points`.
double contour_error_mm(const std::vector<CubicSpan>& spans, const std::vector<Vec5>& points);

}  // namespace truecut::interp
