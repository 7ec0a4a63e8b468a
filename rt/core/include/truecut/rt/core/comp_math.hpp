// The per-cycle arithmetic of truecut_comp as pure functions: fade ramp,
// magnitude clamp, rate limit, parameter sanitising. No state, no HAL, no
// allocation; noexcept.
#pragma once

// Part of the real-time core: include "truecut/rt/comp.hpp" (std and Eigen only).

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>

namespace truecut::rt::comp {

using Vec3 = Eigen::Vector3d;

// Every component exactly 0 (cheaper in the cycle than Eigen's isZero).
inline bool exactly_zero(const Vec3& v) noexcept {
  return v.x() == 0.0 && v.y() == 0.0 && v.z() == 0.0;
}

// Fade gain of a fade progress u in [0, 1]: the quintic "smootherstep"
// 6u^5 - 15u^4 + 10u^3. Its first and second derivatives vanish at both ends,
// so a linear ramp of u gives a correction that starts and stops with zero
// velocity and zero acceleration (C2 in time): a servo sees no kink.
// g(1 - u) = 1 - g(u), so a cross-fade of two sources keeps the sum of gains 1.
inline double fade_gain(double u) noexcept {
  u = std::clamp(u, 0.0, 1.0);
  return u * u * u * (u * (u * 6.0 - 15.0) + 10.0);
}

// Largest slope of fade_gain (at u = 1/2): 15/8.
inline constexpr double kFadeGainMaxSlope = 1.875;

// Moves the fade progress `u` towards `target` (0 or 1) by one cycle: a full
// fade takes fade_time_s. fade_time_s == 0 jumps (the rate limit still acts).
inline double advance_fade(double u, double target, double dt_s, double fade_time_s) noexcept {
  if (!(fade_time_s > 0.0) || u == target) return target;
  const double step = dt_s / fade_time_s;
  const double next = u < target ? u + step : u - step;
  // Within rounding of the target counts as there, so that a fade of
  // fade_time / dt cycles ends on its last cycle.
  if (std::abs(target - next) <= 1e-9 * step || (next - target) * (u - target) < 0.0) return target;
  return next;
}

struct Limited {
  Vec3 value;
  bool limited;  // the limit changed the value
};

// Scales `c` down to length max_mm, keeping its direction.
inline Limited limit_magnitude(const Vec3& c, double max_mm) noexcept {
  const double n = c.norm();
  if (n <= max_mm) return {c, false};
  return {c * (max_mm / n), true};  // n > max_mm >= 0
}

// limit_magnitude() whose result's computed length is never above max_mm,
// not even by rounding: the hard bound on the output.
inline Limited limit_magnitude_hard(const Vec3& c, double max_mm) noexcept {
  Limited r = limit_magnitude(c, max_mm);
  for (int i = 0; i < 4 && r.value.norm() > max_mm; ++i) {
    r.value *= 1.0 - 4e-16;
    r.limited = true;
  }
  if (r.value.norm() > max_mm) r.value.setZero();  // cannot happen
  return r;
}

// Moves from `previous` towards `target` by at most max_step_mm (Euclidean):
// the vector rate limit, so the correction never steps further than
// max rate x period, in any direction.
inline Limited limit_rate(const Vec3& target, const Vec3& previous, double max_step_mm) noexcept {
  const Vec3 d = target - previous;
  const double n = d.norm();
  if (n <= max_step_mm) return {target, false};
  return {previous + d * (max_step_mm / n), true};  // n > max_step_mm >= 0
}

// The compensation's correction bound: the longest correction vector, mm,
// unless the integrator sets another (the `max-correction` pin). Every other
// default of a correction bound in truecut derives from this one or says why
// it overrides it.
inline constexpr double kDefaultMaxCorrectionMm = 1.0;

// The tool-orientation correction's limits default to the translation's seen
// at a lever of 100 mm (a rotation of r rad moves a point 100 mm up the tool
// by 100 r mm): bound 0.01 rad (0.57 deg), rate 0.1 rad/s, and (HAL pins)
// acceleration 10 rad/s^2, jerk 1000 rad/s^3.
inline constexpr double kToolLeverMm = 100.0;
inline constexpr double kDefaultMaxTiltRad = kDefaultMaxCorrectionMm / kToolLeverMm;

// The tunables, as the pins hold them.
struct CompLimits {
  double max_correction_mm = kDefaultMaxCorrectionMm;  // length of the correction vector
  double max_rate_mm_per_s = 10.0;                     // speed of the correction vector
  double fade_time_s = 1.0;                            // duration of a full fade in or out
  // Acceleration of the correction vector; 0: not limited (the core's
  // default; the HAL pin's default is kDefaultMaxAccelMmPerS2).
  double max_accel_mm_per_s2 = 0.0;
  // Jerk of the correction vector; 0: not limited (the core's default; the
  // HAL pin's default is kDefaultMaxJerkMmPerS3).
  double max_jerk_mm_per_s3 = 0.0;
  // The same four for the rotation of the tool (rotation vector, rad): its
  // angle, angular speed, acceleration and jerk.
  double max_tilt_rad = kDefaultMaxTiltRad;
  double max_tilt_rate_rad_per_s = 10.0 / kToolLeverMm;
  double max_tilt_accel_rad_per_s2 = 0.0;
  double max_tilt_jerk_rad_per_s3 = 0.0;
};

// The `max-accel` pin's default, mm/s^2: 0.1 g. A full default fade (1 mm in
// 1 s, peak 5.8 mm/s^2) is far below it; a step of the wanted correction
// (a lowered bound, fade-time 0, a swap) reaches max-rate in 10 ms.
inline constexpr double kDefaultMaxAccelMmPerS2 = 1000.0;

// The `max-jerk` pin's default, mm/s^3 (100 m/s^3): max-accel is reached in
// 10 ms. A default fade (smootherstep of 1 mm in 1 s) peaks at 60 mm/s^3,
// the soft-CNC loop's (0.5 mm in 0.2 s) at 3750 mm/s^3: both far below.
inline constexpr double kDefaultMaxJerkMmPerS3 = 1.0e5;

// The tilt pins' defaults: the translation's over the lever.
inline constexpr double kDefaultMaxTiltAccelRadPerS2 = kDefaultMaxAccelMmPerS2 / kToolLeverMm;
inline constexpr double kDefaultMaxTiltJerkRadPerS3 = kDefaultMaxJerkMmPerS3 / kToolLeverMm;

// Replaces each invalid tunable (not finite, or negative) by its safe value:
// max correction 0 (the correction goes to zero), max rate 0 (the correction
// holds), fade time 0. Returns whether all were valid. (The servo cycle uses
// adopt_limits() instead, which keeps the last valid values.)
inline bool sanitize(const CompLimits& raw, CompLimits& safe) noexcept {
  auto ok = [](double v) { return std::isfinite(v) && v >= 0.0; };
  safe.max_correction_mm = ok(raw.max_correction_mm) ? raw.max_correction_mm : 0.0;
  safe.max_rate_mm_per_s = ok(raw.max_rate_mm_per_s) ? raw.max_rate_mm_per_s : 0.0;
  safe.fade_time_s = ok(raw.fade_time_s) ? raw.fade_time_s : 0.0;
  return ok(raw.max_correction_mm) && ok(raw.max_rate_mm_per_s) && ok(raw.fade_time_s);
}

// The servo cycle's parameter discipline: each tunable that is valid is
// used and remembered in `last_good`; each invalid one (NaN, infinite,
// negative, or a max rate of 0, which could never bring the correction back
// to zero) is replaced by its last valid value, so that the correction can
// always be faded to zero at limits the integrator once set. Returns whether
// all were valid (false: the kBadParameter fault).
inline bool adopt_limits(const CompLimits& raw, CompLimits& last_good, CompLimits& use) noexcept {
  auto ok = [](double v) { return std::isfinite(v) && v >= 0.0; };
  bool all = true;
  auto take = [&](double v, double& good, bool valid) {
    if (valid)
      good = v;
    else
      all = false;
    return good;
  };
  use.max_correction_mm =
      take(raw.max_correction_mm, last_good.max_correction_mm, ok(raw.max_correction_mm));
  use.max_rate_mm_per_s = take(raw.max_rate_mm_per_s, last_good.max_rate_mm_per_s,
                               ok(raw.max_rate_mm_per_s) && raw.max_rate_mm_per_s > 0.0);
  use.fade_time_s = take(raw.fade_time_s, last_good.fade_time_s, ok(raw.fade_time_s));
  use.max_accel_mm_per_s2 =
      take(raw.max_accel_mm_per_s2, last_good.max_accel_mm_per_s2, ok(raw.max_accel_mm_per_s2));
  use.max_jerk_mm_per_s3 =
      take(raw.max_jerk_mm_per_s3, last_good.max_jerk_mm_per_s3, ok(raw.max_jerk_mm_per_s3));
  use.max_tilt_rad = take(raw.max_tilt_rad, last_good.max_tilt_rad, ok(raw.max_tilt_rad));
  use.max_tilt_rate_rad_per_s =
      take(raw.max_tilt_rate_rad_per_s, last_good.max_tilt_rate_rad_per_s,
           ok(raw.max_tilt_rate_rad_per_s) && raw.max_tilt_rate_rad_per_s > 0.0);
  use.max_tilt_accel_rad_per_s2 =
      take(raw.max_tilt_accel_rad_per_s2, last_good.max_tilt_accel_rad_per_s2,
           ok(raw.max_tilt_accel_rad_per_s2));
  use.max_tilt_jerk_rad_per_s3 =
      take(raw.max_tilt_jerk_rad_per_s3, last_good.max_tilt_jerk_rad_per_s3,
           ok(raw.max_tilt_jerk_rad_per_s3));
  return all;
}

// Fastest speed from which a motion braking by dv_max per cycle of dt_s
// stops within d (the discrete braking curve). From s = (k + t) dv_max,
// 0 <= t < 1, the speeds of the following cycles are s, s - dv_max, ...,
// t dv_max, then 0: a distance of dv_max dt (k + 1)(t + k/2). The inverse is
// piecewise linear between the points k(k + 1)/2 and exact along a braking
// run: braking_speed(d - s dt) = s - dv_max for s = braking_speed(d). (The
// smooth curve through the same points lets the speed exceed d/dt for the
// last cycle, i.e. overshoot by up to ~12 % of a cycle's step.) Also the
// curve of acceleration against the distance to a velocity limit, with the
// jerk step in place of dv_max.
inline double braking_speed(double d, double dv_max, double dt_s) noexcept {
  if (!(d > 0.0) || !(dv_max > 0.0) || !(dt_s > 0.0)) return 0.0;
  const double x = d / (dv_max * dt_s);
  if (!std::isfinite(x)) return std::numeric_limits<double>::max();
  double k = std::floor(0.5 * (std::sqrt(1.0 + 8.0 * x) - 1.0));
  if ((k + 1.0) * (k + 2.0) * 0.5 <= x) k += 1.0;  // rounding of the square root
  if (k > 0.0 && k * (k + 1.0) * 0.5 > x) k -= 1.0;
  const double t = std::min(1.0, (x - k * (k + 1.0) * 0.5) / (k + 1.0));
  return dv_max * (k + t);
}

// One cycle of the correction's motion: position y and velocity v (mm,
// mm/s) move towards `target` (this cycle's wanted correction, of length
// <= bound; target_prev was last cycle's) so that |velocity| <= max_rate
// and, if max_accel > 0, |change of velocity| <= max_accel x dt in every
// cycle (vector norms). A target whose own motion is within the limits is
// followed exactly (`limited` false); otherwise the output brakes towards
// the target along the discrete braking curve, relative to the target's own
// velocity, and lands on it exactly once it can. It also brakes before the
// sphere of radius `bound`, so that it never has to be clipped there.
struct Motion {
  Vec3 position;
  Vec3 velocity;
  bool limited;
};

inline Motion limit_motion(const Vec3& target, const Vec3& target_prev, const Vec3& y,
                           const Vec3& v, double max_rate, double max_accel, double bound,
                           double dt) noexcept {
  if (!(dt > 0.0)) return {y, Vec3::Zero(), target != y};
  if (!(max_accel > 0.0)) {
    const Limited r = limit_rate(target, y, max_rate * dt);
    return {r.value, (r.value - y) / dt, r.limited};
  }
  const double dv_max = max_accel * dt;
  // Outward speed at p that can still stop before the bound.
  auto outward_ok = [&](const Vec3& p, const Vec3& vel) {
    const double r = p.norm();
    return r == 0.0 || vel.dot(p) / r <= braking_speed(bound - r, dv_max, dt) * (1 + 1e-12);
  };
  const Vec3 v_req = (target - y) / dt;
  if (v_req.norm() <= max_rate && (v_req - v).norm() <= dv_max && outward_ok(target, v_req))
    return {target, v_req, false};
  Vec3 vd = limit_magnitude((target - target_prev) / dt, max_rate).value;
  const Vec3 gap = target - y;
  const double d = gap.norm();
  if (d > 0.0) vd += gap * (std::min(braking_speed(d, dv_max, dt), d / dt) / d);
  const double r = y.norm();
  if (r > 0.0) {  // brake before the bound
    const Vec3 e = y / r;
    const double excess = vd.dot(e) - braking_speed(bound - r, dv_max, dt);
    if (excess > 0.0) vd -= excess * e;
  }
  vd = limit_magnitude(vd, max_rate).value;
  const Vec3 vn = limit_magnitude(limit_rate(vd, v, dv_max).value, max_rate).value;
  return {y + vn * dt, vn, true};
}

// Jerk-limited stops (continuous time): the distance a stop from speed w >= 0
// with zero initial acceleration needs at jerk J and acceleration A, and its
// inverse, the fastest speed from which a stop fits within d.
inline double stop_distance_ja(double w, double A, double J) noexcept {
  if (!(w > 0.0)) return 0.0;
  if (w <= A * A / J) return w * std::sqrt(w / J);
  return 0.5 * w * (w / A + A / J);
}
inline double stop_speed_ja(double d, double A, double J) noexcept {
  if (!(d > 0.0)) return 0.0;
  if (d <= A * A * A / (J * J)) return std::cbrt(d * d * J);
  const double k = A / J;
  return 0.5 * A * (std::sqrt(k * k + 8.0 * d / A) - k);
}

namespace detail {

// Deadbeat landing of the output's error e (relative to a target at t0 moving
// with velocity vt0 and constant acceleration at) in n >= 3 cycles: the minimum-norm
// sequence of n jerks that brings position, velocity and acceleration error
// to zero together (the discrete triple integrator a += dt j, v += dt a,
// p += dt v). Returns whether every cycle of it is within the limits (and
// the bound, along the target's extrapolation); then `first` is the
// acceleration of its first cycle. Fixed work: 2n small steps.
inline bool land(const Vec3& ep, const Vec3& ev, const Vec3& ea, const Vec3& t0, const Vec3& vt0,
                 const Vec3& at, int n, double V, double A, double J, double R, double dt,
                 Vec3& first) noexcept {
  // Scaled units P = p/dt^3, W = v/dt^2, Q = a/dt: a jerk n - m cycles
  // before the end moves the final state by (m(m+1)/2, m, 1) j.
  Eigen::Matrix3d G = Eigen::Matrix3d::Zero();
  for (int m = 1; m <= n; ++m) {
    const Eigen::Vector3d b(0.5 * m * (m + 1), m, 1.0);
    G += b * b.transpose();
  }
  Eigen::Matrix3d adj;  // G^-1 by cofactors (G is positive definite for n >= 3)
  adj(0, 0) = G(1, 1) * G(2, 2) - G(1, 2) * G(2, 1);
  adj(0, 1) = G(0, 2) * G(2, 1) - G(0, 1) * G(2, 2);
  adj(0, 2) = G(0, 1) * G(1, 2) - G(0, 2) * G(1, 1);
  adj(1, 0) = G(1, 2) * G(2, 0) - G(1, 0) * G(2, 2);
  adj(1, 1) = G(0, 0) * G(2, 2) - G(0, 2) * G(2, 0);
  adj(1, 2) = G(0, 2) * G(1, 0) - G(0, 0) * G(1, 2);
  adj(2, 0) = G(1, 0) * G(2, 1) - G(1, 1) * G(2, 0);
  adj(2, 1) = G(0, 1) * G(2, 0) - G(0, 0) * G(2, 1);
  adj(2, 2) = G(0, 0) * G(1, 1) - G(0, 1) * G(1, 0);
  const double det = G(0, 0) * adj(0, 0) + G(0, 1) * adj(1, 0) + G(0, 2) * adj(2, 0);
  Eigen::Matrix3d rhs;  // rows: final position, velocity, acceleration; columns: x y z
  const double N = n;
  for (int k = 0; k < 3; ++k) {
    const double P = ep[k] / (dt * dt * dt), W = ev[k] / (dt * dt), Q = ea[k] / dt;
    rhs(0, k) = -(P + N * W + Q * 0.5 * N * (N + 1));
    rhs(1, k) = -(W + N * Q);
    rhs(2, k) = -Q;
  }
  const Eigen::Matrix3d lambda = (adj / det) * rhs;
  if (!lambda.allFinite()) return false;
  Vec3 a = ea, v = ev, p = ep, tv = vt0, tp = t0;
  for (int i = 0; i < n; ++i) {
    const int m = n - i;
    const Vec3 j = lambda.transpose() * Eigen::Vector3d(0.5 * m * (m + 1), m, 1.0);
    a += dt * j;
    v += dt * a;
    p += dt * v;
    tv += dt * at;
    tp += dt * tv;
    if (i == 0) first = at + a;
    if (j.norm() > J || (at + a).norm() > A || (tv + v).norm() > V || (tp + p).norm() > R)
      return false;
  }
  return true;
}

}  // namespace detail

// The velocity at which a motion at velocity v ends when its acceleration a
// is brought to zero by steps of dj per cycle (the jerk limit), straight:
// v + dt (a + (|a| - dj) + ... ) along a.
inline Vec3 terminal_velocity(const Vec3& v, const Vec3& a, double dj, double dt) noexcept {
  const double na = a.norm();
  if (!(na > 0.0)) return v;
  const double k = std::floor(na / dj);
  const double sum = (k + 1.0) * na - dj * k * (k + 1.0) * 0.5;
  return v + a * (dt * sum / na);
}

// limit_motion() with a jerk limit as well: position y, velocity v and
// acceleration a (of the output, mm, mm/s, mm/s^2) move towards `target` so
// that in every cycle |velocity| <= max_rate, |acceleration| <= max_accel and
// |change of acceleration| <= max_jerk x dt (vector norms, as measured by
// differences of the outputs). In that order of preference:
// - a target that the output was on last cycle and whose own motion is
//   within the limits is followed exactly;
// - a deadbeat landing on the target's extrapolation (its velocity and
//   acceleration from target, target_prev, target_prev2) in n = 3, 6, ...
//   48 cycles, whose every cycle is within the limits; once on, followed;
// - otherwise the output closes the gap along a jerk-limited braking curve
//   (desired velocity), its acceleration along the discrete braking curve of
//   the velocity error, braking before max_rate and before the sphere of
//   radius `bound`.
// max_accel 0 (not limited) is taken as 2 max_rate / dt, the largest change
// of velocity the rate limit allows.
struct JerkMotion {
  Vec3 position;
  Vec3 velocity;
  Vec3 acceleration;
  bool limited;
};

inline JerkMotion limit_motion_jerk(const Vec3& target, const Vec3& target_prev,
                                    const Vec3& target_prev2, const Vec3& y, const Vec3& v,
                                    const Vec3& a, double max_rate, double max_accel,
                                    double max_jerk, double bound, double dt) noexcept {
  const double V = max_rate, J = max_jerk, R = bound;
  if (!(dt > 0.0)) return {y, Vec3::Zero(), Vec3::Zero(), target != y};
  const double A = max_accel > 0.0 ? max_accel : 2.0 * max_rate / dt;
  const double dj = J * dt;  // largest change of acceleration per cycle
  // The speed from which a jerk-limited stop fits within d, with two cycles
  // of margin for the discretisation.
  auto stop_speed = [&](double d) {
    const double s = stop_speed_ja(d, A, J);
    const double d2 = d - 2.0 * s * dt;
    return d2 > 0.0 ? std::min(s, stop_speed_ja(d2, A, J)) : 0.0;
  };
  // Moving at vel with acceleration acc at p, can the output still stop
  // before the bound?
  auto outward_ok = [&](const Vec3& p, const Vec3& vel, const Vec3& acc) {
    const double r = p.norm();
    if (r == 0.0) return true;
    const Vec3 e = p / r;
    double w = vel.dot(e);
    const double al = acc.dot(e);
    if (al > 0.0) w += al * al / (2.0 * J) + al * dt;  // while the acceleration ramps down
    return w <= stop_speed(R - r) * (1 + 1e-12);
  };
  const Vec3 vt = (target - target_prev) / dt;
  const Vec3 vt0 = (target_prev - target_prev2) / dt;
  const Vec3 at = (vt - vt0) / dt;
  // Following (the output was on the target last cycle, to within a
  // thousandth of a cycle's jerk step): the target itself, if its motion is
  // within the limits.
  if ((y - target_prev).norm() <= 1e-3 * dj * dt * dt) {
    const Vec3 v_req = (target - y) / dt;
    const Vec3 a_req = (v_req - v) / dt;
    if (v_req.norm() <= V && a_req.norm() <= A && (a_req - a).norm() <= dj &&
        terminal_velocity(v_req, a_req, dj, dt).norm() <= V && outward_ok(target, v_req, a_req))
      return {target, v_req, a_req, false};
  }
  auto take = [&](const Vec3& an) -> JerkMotion {
    const Vec3 vn = limit_magnitude(v + an * dt, V).value;  // (the braking keeps it within)
    const Vec3 yn = y + vn * dt;
    const Vec3 vm = (yn - y) / dt;
    return {yn, vm, (vm - v) / dt, true};
  };
  // Landing on the target's extrapolation, as fast as the limits let it.
  if (vt0.norm() <= V && at.norm() <= A) {
    for (int n : {3, 6, 12, 24, 48}) {
      Vec3 an;
      if (detail::land(y - target_prev, v - vt0, a - at, target_prev, vt0, at, n, V, A, J, R, dt,
                       an))
        return take(an);
    }
  }
  // Desired velocity: the target's own, plus closing the gap.
  Vec3 vd = limit_magnitude(vt, V).value;
  const Vec3 gap = target - y;
  const double d = gap.norm();
  if (d > 0.0) vd += gap * (std::min(stop_speed(d), d / dt) / d);
  const double r = y.norm();
  if (r > 0.0) {  // brake before the bound
    const Vec3 e = y / r;
    const double excess = vd.dot(e) - stop_speed(R - r);
    if (excess > 0.0) vd -= excess * e;
  }
  vd = limit_magnitude(vd, V).value;
  // Desired acceleration: close the velocity error along the discrete
  // braking curve of the acceleration, and brake before max_rate.
  const Vec3 ev = vd - v;
  const double dv = ev.norm();
  Vec3 ad = Vec3::Zero();
  if (dv > 0.0) ad = ev * (std::min({braking_speed(dv, dj, dt), dv / dt, A}) / dv);
  const double sv = v.norm();
  if (sv > 0.0) {
    const Vec3 e = v / sv;
    const double excess = ad.dot(e) - braking_speed(V - sv, dj, dt);
    if (excess > 0.0) ad -= excess * e;
  }
  // The acceleration towards ad within the jerk and acceleration limits,
  // then as far along the way from the safest one (the acceleration reduced
  // by one jerk step) as keeps the velocity viable (terminal_velocity within
  // max_rate) and the position within the bound.
  const Vec3 want = limit_magnitude(limit_rate(ad, a, dj).value, A).value;
  const double na = a.norm();
  const Vec3 safe = na > dj ? Vec3(a * (1.0 - dj / na)) : Vec3::Zero();
  auto ok = [&](const Vec3& acc) {
    const Vec3 vn = v + acc * dt;
    return terminal_velocity(vn, acc, dj, dt).norm() <= V && (y + vn * dt).norm() <= R;
  };
  Vec3 an = want;
  if (!ok(want)) {
    double lo = 0.0, hi = 1.0;
    for (int i = 0; i < 24; ++i) {
      const double mid = 0.5 * (lo + hi);
      (ok(safe + mid * (want - safe)) ? lo : hi) = mid;
    }
    an = safe + lo * (want - safe);
  }
  return take(an);
}

}  // namespace truecut::rt::comp
