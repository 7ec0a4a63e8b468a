#include "truecut/sim/servo_model.hpp"

#include <algorithm>

#include "truecut/sim/effects/backlash.hpp"

namespace truecut::sim {

namespace {

constexpr double kMaxSubstepS = 25e-6;
constexpr int kMaxSubsteps = 4096;

double sign(double v) noexcept {
  return v > 0.0 ? 1.0 : (v < 0.0 ? -1.0 : 0.0);
}

}  // namespace

ServoState servo_start(double pos) noexcept {
  ServoState s;
  s.pos = s.table = s.prev_cmd = pos;
  return s;
}

int servo_substeps(double period_s) noexcept {
  const double n = std::ceil(period_s / kMaxSubstepS);
  if (!(n >= 1.0)) return 1;
  return n > kMaxSubsteps ? kMaxSubsteps : int(n);
}

namespace {

double velocity_reference(const ServoParams& p, ServoState& s, double cmd,
                          double period_s) noexcept {
  const double enc = encoder_reading(p, s.pos);
  const double v_ref = p.ff1 * (cmd - s.prev_cmd) / period_s + p.kv_per_s * (cmd - enc);
  s.prev_cmd = cmd;
  return v_ref;
}

void substeps(const ServoParams& p, ServoState& s, double v_ref, double period_s, int n) noexcept {
  const double h = period_s / n;
  const double a_max = std::abs(p.max_accel);
  for (int i = 0; i < n; ++i) {
    const double e_v = v_ref - s.vel;
    const double a_pi = p.vel_kp_per_s * e_v + p.vel_ki_per_s2 * s.vel_integral;
    const double a_drv = std::clamp(a_pi, -a_max, a_max);
    const bool winding_up = a_pi != a_drv && sign(e_v) == sign(a_pi);
    if (!winding_up) s.vel_integral += h * e_v;

    double a;
    if (s.vel == 0.0) {
      // Sticking until the drive overcomes static (Coulomb) friction.
      a = std::abs(a_drv) <= p.coulomb_accel ? 0.0 : a_drv - p.coulomb_accel * sign(a_drv);
    } else {
      a = a_drv - p.coulomb_accel * sign(s.vel) - p.viscous_per_s * s.vel;
    }
    double v_new = s.vel + h * a;
    // Friction can stop the axis but not reverse it within a sub-step.
    if (p.coulomb_accel > 0.0 && s.vel != 0.0 && sign(v_new) != sign(s.vel)) v_new = 0.0;
    // Position exact for the sub-step's constant acceleration (h·v_new
    // alone would lead the true position by h/2·v: 12.5 µs of travel).
    s.pos += h * 0.5 * (s.vel + v_new);
    s.vel = v_new;
    if (p.backlash_play > 0.0)
      s.table = backlash_table_position(s.table, s.pos, p.backlash_play);
    else
      s.table = s.pos;
  }
}

}  // namespace

void servo_step(const ServoParams& p, ServoState& s, double cmd, double period_s) noexcept {
  const double v_ref = velocity_reference(p, s, cmd, period_s);
  substeps(p, s, v_ref, period_s, servo_substeps(period_s));
}

void servo_step(const ServoParams& p, ServoState& s, double cmd, double period_s,
                ServoLinearCache& cache) noexcept {
  const double v_ref = velocity_reference(p, s, cmd, period_s);
  const int n = servo_substeps(period_s);
  if (!servo_linear_step(p, s, v_ref, period_s, n, cache)) substeps(p, s, v_ref, period_s, n);
}

}  // namespace truecut::sim
