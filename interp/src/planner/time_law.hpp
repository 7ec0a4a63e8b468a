// Jerk-limited one-dimensional motion along a segment: velocity changes with
// zero acceleration at both ends (the "S" of an S-curve), their distance, and
// the law over a segment of given length, entry and exit speed.
#pragma once

#include "truecut/interp/plan_segment.hpp"

namespace truecut::interp::plan {

struct LawLimits {
  double v = 0;  // largest speed along the path parameter
  double a = 0;  // largest |acceleration|
  double j = 0;  // largest |jerk|
};

// Time of a velocity change by dv (>= 0) from and to zero acceleration.
double change_time_s(double dv, double a_max, double j_max);
// Distance covered while changing from v0 to v1 (either order).
double change_distance(double v0, double v1, double a_max, double j_max);
// Highest speed (<= lim.v) reachable from v0 within `length`.
double reachable_speed(double v0, double length, const LawLimits& lim);
// The law from v0 to v1 over `length` (change_distance(v0, v1) must not
// exceed length by more than rounding), cruising as fast as lim allows.
TimeLaw make_law(double length, double v0, double v1, const LawLimits& lim);
// Standing still for `duration_s`.
TimeLaw make_hold(double duration_s);

}  // namespace truecut::interp::plan
