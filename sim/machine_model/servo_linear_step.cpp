#include "truecut/sim/servo_linear_step.hpp"

#include <cmath>

#include "truecut/sim/effects/backlash.hpp"
#include "truecut/sim/servo_model.hpp"

namespace truecut::sim {

namespace {

// An affine map x ↦ m[:, 0..2]·x + m[:, 3]·u + m[:, 4]·c of (v, ∫e_v, p),
// the period's constant inputs in the last columns by linearity: u the
// velocity reference, c the Coulomb friction of the direction it keeps.
struct Affine {
  double m[3][5];
};

Affine compose(const Affine& a, const Affine& b) noexcept {  // a ∘ b
  Affine r;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 5; ++j) {
      double v = j >= 3 ? a.m[i][j] : 0.0;
      for (int k = 0; k < 3; ++k)
        v += a.m[i][k] * b.m[k][j];
      r.m[i][j] = v;
    }
  }
  return r;
}

void make_map(const ServoParams& p, double period_s, int n, ServoPeriodMap& out) noexcept {
  out.period_s = period_s;
  out.vel_kp_per_s = p.vel_kp_per_s;
  out.vel_ki_per_s2 = p.vel_ki_per_s2;
  out.viscous_per_s = p.viscous_per_s;
  out.usable = false;

  const double h = period_s / n;
  const double kp = p.vel_kp_per_s, ki = p.vel_ki_per_s2, k = kp + p.viscous_per_s;
  if (!(ki > 0.0) || !(k > 0.0) || !std::isfinite(h * k) || !std::isfinite(h * ki)) return;
  // One sub-step: v' = a11 v + a12 I + h·Kp u − h c, I' = I − h v + h u,
  // p' = p + h/2 (v + v').
  const double a11 = 1.0 - h * k, a12 = h * ki, a21 = -h;
  out.a11 = a11, out.a12 = a12, out.a21 = a21;
  // Eigenvalues of [[a11, a12], [a21, 1]]: (1 − h·K/2) ± h·√(K²/4 − Ki),
  // the discriminant formed without the cancellation of τ²/4 − Δ.
  const double half = 1.0 - 0.5 * h * k, disc = k * k / 4.0 - ki;
  if (disc < 0.0) {
    out.re = half, out.im = h * std::sqrt(-disc);
    if (!(out.re * out.re + out.im * out.im < 1.0) || !(out.im > 1e-12)) return;
  } else {
    const double r = h * std::sqrt(disc);
    out.l1 = half + r, out.l2 = half - r, out.im = 0.0;
    if (!(std::abs(out.l1) < 1.0) || !(std::abs(out.l2) < 1.0) || !(r > 1e-12)) return;
  }

  Affine step{};
  step.m[0][0] = a11, step.m[0][1] = a12, step.m[0][3] = h * kp;
  step.m[1][0] = a21, step.m[1][1] = 1.0, step.m[1][3] = h;
  step.m[2][0] = 0.5 * h * (1.0 + a11), step.m[2][1] = 0.5 * h * a12, step.m[2][2] = 1.0;
  step.m[2][3] = 0.5 * h * h * kp;
  step.m[0][4] = -h, step.m[2][4] = -0.5 * h * h;
  Affine power{};  // identity
  for (int i = 0; i < 3; ++i)
    power.m[i][i] = 1.0;
  for (unsigned e = unsigned(n); e != 0; e >>= 1) {
    if (e & 1u) power = compose(power, step);
    if (e > 1u) step = compose(step, step);
  }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 5; ++j) {
      if (!std::isfinite(power.m[i][j])) return;
      out.m[i][j] = power.m[i][j];
    }
  out.usable = true;
}

const ServoPeriodMap& map_for(const ServoParams& p, double period_s, int n,
                              ServoLinearCache& cache) noexcept {
  for (const ServoPeriodMap& m : cache.maps)
    if (m.period_s == period_s && m.vel_kp_per_s == p.vel_kp_per_s &&
        m.vel_ki_per_s2 == p.vel_ki_per_s2 && m.viscous_per_s == p.viscous_per_s &&
        m.period_s > 0.0)
      return m;
  ServoPeriodMap& m = cache.maps[cache.next];
  cache.next = (cache.next + 1) % cache.maps.size();
  make_map(p, period_s, n, m);
  return m;
}

// max over i >= 0 of |w · A^i · d| is at most this, A the (v, ∫e_v) matrix
// of one sub-step (its eigenvalues of modulus below 1).
double transient_bound(const ServoPeriodMap& m, double w0, double w1, double d0,
                       double d1) noexcept {
  const double wd = w0 * d0 + w1 * d1;
  const double ad0 = m.a11 * d0 + m.a12 * d1, ad1 = m.a21 * d0 + d1;
  const double wad = w0 * ad0 + w1 * ad1;
  if (m.im > 0.0) {
    // w·A^i·d = 2 Re(λ1^i · w(A − λ2)d / (λ1 − λ2)), λ1,2 = re ± i·im.
    const double x = wad - m.re * wd, y = m.im * wd;
    return std::sqrt(x * x + y * y) / m.im;
  }
  return (std::abs(wad - m.l2 * wd) + std::abs(wad - m.l1 * wd)) / (m.l1 - m.l2);
}

}  // namespace

bool servo_linear_step(const ServoParams& p, ServoState& s, double v_ref, double period_s, int n,
                       ServoLinearCache& cache) noexcept {
  if (!(p.max_accel != 0.0) || !std::isfinite(v_ref) || !(p.coulomb_accel >= 0.0)) return false;
  const bool coulomb = p.coulomb_accel > 0.0;
  // Coulomb friction is a constant force while the axis keeps its
  // direction: the motor must be moving, towards the reference's sign.
  const double direction = v_ref > 0.0 ? 1.0 : -1.0;
  if (coulomb && !(s.vel * direction > 0.0)) return false;
  const ServoPeriodMap& m = map_for(p, period_s, n, cache);
  if (!m.usable) return false;

  // The (v, ∫e_v) state's distance from its fixed point (u, (B·u + c)/Ki).
  const double c = coulomb ? p.coulomb_accel * direction : 0.0;
  const double held = p.viscous_per_s * v_ref + c;  // the PI output there
  const double d0 = s.vel - v_ref;
  const double d1 = s.vel_integral - held / p.vel_ki_per_s2;
  // The PI output Kp·(u − v) + Ki·∫e_v = B·u + c + (−Kp, Ki)·A^i·d.
  const double a_bound =
      std::abs(held) + transient_bound(m, -p.vel_kp_per_s, p.vel_ki_per_s2, d0, d1);
  if (!(a_bound < std::abs(p.max_accel) * (1.0 - 1e-9))) return false;
  if (coulomb || p.backlash_play > 0.0) {
    const double v_bound = transient_bound(m, 1.0, 0.0, d0, d1);
    const bool keeps_sign = std::abs(v_ref) > v_bound * (1.0 + 1e-9);
    if (!(keeps_sign || (!coulomb && v_bound == 0.0))) return false;
  }

  const double x[3] = {s.vel, s.vel_integral, s.pos};
  double y[3];
  for (int i = 0; i < 3; ++i)
    y[i] =
        m.m[i][0] * x[0] + m.m[i][1] * x[1] + m.m[i][2] * x[2] + m.m[i][3] * v_ref + m.m[i][4] * c;
  s.vel = y[0], s.vel_integral = y[1], s.pos = y[2];
  s.table =
      p.backlash_play > 0.0 ? backlash_table_position(s.table, s.pos, p.backlash_play) : s.pos;
  return true;
}

}  // namespace truecut::sim
