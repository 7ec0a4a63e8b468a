#include "limits.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "output_map.hpp"

namespace truecut::interp::plan {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Shares of each joint limit (see limits.hpp).
constexpr double kAccCurve = 0.5, kAccPath = 0.5;
constexpr double kJerkCurve = 0.2, kJerkCross = 0.2, kJerkPath = 0.3;
constexpr double kJerkKink = 0.15, kJerkStep = 0.15;
constexpr double kSafety = 1.05;  // on sampled derivative bounds

struct Stencil {
  Joint5 d1, d2, d3;
};

// The joints at u + du (see evaluate_near); joints_at is du = 0.
Joint5 joints_near(const Move& m, double u, double du, double w) {
  const MappedPoint mp = map_point(m.tcp, m.kinematics, w, evaluate_near(m.piece, u, du), {});
  return {mp.joints.x_mm, mp.joints.y_mm, mp.joints.z_mm, mp.joints.a_deg, mp.joints.c_deg};
}

// Differences over h around u; the offsets are kept apart from u (see
// evaluate_near): at u = 6e8 mm along an arc of 1e8 turns, u +- h rounds to
// 1e-7 mm, which the third difference over 2e-3 mm made a jerk bound 10
// times too high (the arc planned 11 % slow).
Stencil stencil(const Move& m, double u, double h, double w) {
  const Joint5 qm2 = joints_near(m, u, -2 * h, w), qm1 = joints_near(m, u, -h, w),
               q0 = joints_near(m, u, 0, w), qp1 = joints_near(m, u, h, w),
               qp2 = joints_near(m, u, 2 * h, w);
  Stencil s;
  for (int j = 0; j < 5; ++j) {
    s.d1[j] = (qp1[j] - qm1[j]) / (2 * h);
    s.d2[j] = (qp1[j] - 2 * q0[j] + qm1[j]) / (h * h);
    s.d3[j] = (qp2[j] - 2 * qp1[j] + 2 * qm1[j] - qm2[j]) / (2 * h * h * h);
  }
  return s;
}

double feed_metric_rate(const Vec5& dp, FeedMetric metric, double w) {
  if (metric == FeedMetric::kXyz) return std::sqrt(dp[0] * dp[0] + dp[1] * dp[1] + dp[2] * dp[2]);
  return std::sqrt(dp[3] * dp[3] + dp[4] * dp[4]) / w;
}

double step_for(double span) {
  return std::max(span / 16.0, 2e-5);
}

}  // namespace

Joint5 joints_at(const Move& m, double u, double w) {
  return joints_near(m, u, 0.0, w);
}

int stretches(const Move& m, double w) {
  const PathPiece& p = m.piece;
  int n = 1;
  if (p.kind == PathPiece::kArc)
    n = std::max(n, static_cast<int>(std::ceil(std::abs(p.sweep_rad) / (std::numbers::pi / 8))));
  if (m.tcp) {
    const Vec5 d = sub(evaluate(p, p.length), evaluate(p, 0));
    const double rot_deg = std::hypot(d[3], d[4]) / w;
    n = std::max({n, static_cast<int>(std::ceil(p.length / 10.0)),
                  static_cast<int>(std::ceil(rot_deg / 5.0))});
  }
  return std::clamp(n, 1, 512);
}

DerivativeBounds derivative_bounds(const Move& m, double u0, double u1, double w) {
  DerivativeBounds b;
  const double span = u1 - u0;
  double h = step_for(span);
  int samples = 9;
  double h_feed = h;
  if (m.piece.kind == PathPiece::kArc && m.piece.length > 0) {
    // An arc of many turns has stretches of several turns each (at most 512
    // stretches). A difference across an angle x reads the chord, sin(x)/x
    // of the arc (a 1000-turn arc ran 10 % over its feed): the step stays
    // within 2e-3 rad (7e-7 low). And the samples stay within pi/16 of each
    // other, so that no joint's peak lies unseen between them (up to 1024
    // samples a stretch: arcs of up to 32,000 turns; more is no program).
    const double angle_per_u = std::abs(m.piece.sweep_rad) / m.piece.length;
    h = std::max(std::min(h, 2e-3 / angle_per_u), 2e-5);
    const double spaced = std::ceil(span * angle_per_u / (std::numbers::pi / 16)) + 1;
    samples = static_cast<int>(std::clamp(spaced, 9.0, 1024.0));
    // The feed has no safety factor: its rate is read over 2e-5 rad, where
    // the chord is 7e-11 short (7e-7 over 2e-3 rad let an arc of 1e8 turns
    // run 1.6e-6 over its feed); with the offsets apart from u the
    // rounding stays near 1e-11 as well.
    h_feed = std::min(h, 2e-5 / angle_per_u);
  }
  for (int i = 0; i < samples; ++i) {
    const double u = u0 + span * i / (samples - 1);
    const Stencil s = stencil(m, u, h, w);
    for (int j = 0; j < 5; ++j) {
      b.d1[j] = std::max(b.d1[j], std::abs(s.d1[j]));
      b.d2[j] = std::max(b.d2[j], std::abs(s.d2[j]));
      b.d3[j] = std::max(b.d3[j], std::abs(s.d3[j]));
    }
    const Vec5 pa = evaluate_near(m.piece, u, -h_feed), pb = evaluate_near(m.piece, u, h_feed);
    Vec5 dp;
    for (int k = 0; k < 5; ++k)
      dp[k] = (pb[k] - pa[k]) / (2 * h_feed);
    b.feed_rate_per_u = std::max(b.feed_rate_per_u, feed_metric_rate(dp, m.metric, w));
    b.feed_rate_per_u_out =
        std::max(b.feed_rate_per_u_out, feed_metric_rate(dp, m.blend_metric_out, w));
  }
  // A line in joint space has constant derivatives: its samples are exact.
  const double safety = !m.tcp && m.piece.kind == PathPiece::kLine ? 1.0 : kSafety;
  for (int j = 0; j < 5; ++j) {
    b.d1[j] *= safety;
    b.d2[j] *= safety;
    b.d3[j] *= safety;
  }
  return b;
}

LawLimits law_limits(const Move& m, const DerivativeBounds& b, const MachineLimits& lim) {
  double v = kInf;
  if (std::isfinite(m.feed) && b.feed_rate_per_u > 1e-12) v = m.feed / b.feed_rate_per_u;
  if (m.blend_feed_out > 0 && std::isfinite(m.blend_feed_out) && b.feed_rate_per_u_out > 1e-12)
    v = std::min(v, m.blend_feed_out / b.feed_rate_per_u_out);
  for (int j = 0; j < 5; ++j) {
    const AxisLimits& l = lim.axis[j];
    if (b.d1[j] > 0) v = std::min(v, l.max_velocity / b.d1[j]);
    if (b.d2[j] > 0) v = std::min(v, std::sqrt(kAccCurve * l.max_acceleration / b.d2[j]));
    if (b.d3[j] > 0) v = std::min(v, std::cbrt(kJerkCurve * l.max_jerk / b.d3[j]));
  }
  double a = kInf;
  for (int j = 0; j < 5; ++j) {
    const AxisLimits& l = lim.axis[j];
    if (b.d1[j] > 0) a = std::min(a, kAccPath * l.max_acceleration / b.d1[j]);
    if (b.d2[j] > 0 && v > 0) a = std::min(a, kJerkCross * l.max_jerk / (3 * b.d2[j] * v));
  }
  double jerk = kInf;
  for (int j = 0; j < 5; ++j)
    if (b.d1[j] > 0) jerk = std::min(jerk, kJerkPath * lim.axis[j].max_jerk / b.d1[j]);
  LawLimits out;
  out.v = std::isfinite(v) ? v : 0;
  out.a = std::isfinite(a) ? a : 1.0;
  out.j = std::isfinite(jerk) ? jerk : 1.0;
  return out;
}

double junction_cap(const Move& a, const Move& b, const MachineLimits& lim, double period_s,
                    double w) {
  const double ha = step_for(a.piece.length), hb = step_for(b.piece.length);
  const Stencil sa = stencil(a, a.piece.length, ha, w);
  const Stencil sb = stencil(b, 0.0, hb, w);
  double cap = kInf;
  for (int j = 0; j < 5; ++j) {
    const AxisLimits& l = lim.axis[j];
    const double kink = std::abs(sa.d1[j] - sb.d1[j]);
    const double step = std::abs(sa.d2[j] - sb.d2[j]);
    // Below these the difference is the stencils' own error.
    if (kink > 1e-7 * (1 + std::abs(sa.d1[j])))
      cap = std::min(cap, kJerkKink * l.max_jerk * period_s * period_s / kink);
    if (step > 1e-5 * (1 + std::abs(sa.d2[j]) + std::abs(sb.d2[j])))
      cap = std::min(cap, std::sqrt(kJerkStep * l.max_jerk * period_s / step));
  }
  return cap;
}

}  // namespace truecut::interp::plan
