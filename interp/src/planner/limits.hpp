// Joint derivatives along a piece and the path-parameter limits that keep
// every joint within MachineLimits.
//
// With q(u) the joints along the path parameter u and u(t) the time law,
//   q'   = q_u u'
//   q''  = q_uu u'^2 + q_u u''
//   q''' = q_uuu u'^3 + 3 q_uu u' u'' + q_u u'''
// Bounds D1..D3 of |q_u|, |q_uu|, |q_uuu| over a stretch of path give the
// speed V, acceleration A and jerk J along u that keep every term within
// its share of the joint's limit (shares below). The jerk shares add up to
// 0.7 of the limit; the remaining 0.3 is kept for the steps a junction may
// put into the sampled setpoints (see junction_cap).
#pragma once

#include <array>

#include "path.hpp"
#include "time_law.hpp"

namespace truecut::interp::plan {

using Joint5 = std::array<double, 5>;

struct DerivativeBounds {
  Joint5 d1{}, d2{}, d3{};
  double feed_rate_per_u = 0;      // largest feed-metric length per unit u
  double feed_rate_per_u_out = 0;  // the same in the metric of a blend's outgoing move
};

// Joints at u (u may lie slightly outside the piece: its formula extends).
Joint5 joints_at(const Move& m, double u, double weight);
DerivativeBounds derivative_bounds(const Move& m, double u0, double u1, double weight);
LawLimits law_limits(const Move& m, const DerivativeBounds& b, const MachineLimits& lim);

// Highest speed along u at which the junction from the end of `a` to the
// start of `b` keeps the sampled joint jerk within the limits: the joints'
// first derivatives may kink and their second derivatives may step there.
double junction_cap(const Move& a, const Move& b, const MachineLimits& lim, double period_s,
                    double weight);

// How many stretches a move is split into for its limits.
int stretches(const Move& m, double weight);

}  // namespace truecut::interp::plan
