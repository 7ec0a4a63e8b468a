// The per-cycle arithmetic of truecut_comp as pure functions: fade ramp,
// magnitude clamp, rate limit, parameter sanitising. No state, no HAL, no
// allocation; noexcept.
#pragma once

// Part of the real-time core: include "truecut/rt/comp.hpp" (std and Eigen only).

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

namespace truecut::rt::comp {

using Vec3 = Eigen::Vector3d;

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

// The tunables, as the pins hold them.
struct CompLimits {
  double max_correction_mm = kDefaultMaxCorrectionMm;  // length of the correction vector
  double max_rate_mm_per_s = 10.0;                     // speed of the correction vector
  double fade_time_s = 1.0;                            // duration of a full fade in or out
  // Acceleration of the correction vector; 0: not limited (the core's
  // default; the HAL pin's default is kDefaultMaxAccelMmPerS2).
  double max_accel_mm_per_s2 = 0.0;
};

// The `max-accel` pin's default, mm/s^2: 0.1 g. A full default fade (1 mm in
// 1 s, peak 5.8 mm/s^2) is far below it; a step of the wanted correction
// (a lowered bound, fade-time 0, a swap) reaches max-rate in 10 ms.
inline constexpr double kDefaultMaxAccelMmPerS2 = 1000.0;

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
  return all;
}

// Fastest speed from which a motion braking by dv_max per cycle of dt_s
// stops within d: d = dv_max dt k(k+1)/2 at speed k dv_max.
inline double braking_speed(double d, double dv_max, double dt_s) noexcept {
  if (!(d > 0.0)) return 0.0;
  return dv_max * (std::sqrt(0.25 + 2.0 * d / (dv_max * dt_s)) - 0.5);
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

}  // namespace truecut::rt::comp
