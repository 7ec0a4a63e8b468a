// The servo's sub-steps over one period taken as one step where they are
// linear. With the drive's acceleration limit not reached and the axis
// keeping its direction where Coulomb friction acts (a constant force c
// then), servo_step's N semi-implicit Euler sub-steps are an affine map of
// the state x = (v, ∫e_v, p) and the period's velocity reference u:
//
//   x' = A x + b u + e c    (A, b, e from Kp, Ki, viscous and h = T / N)
//   x_N = A^N x_0 + (Σ_{i<N} A^i) (b u + e c)
//
// so one period is one 3×4 product once A^N is known (computed by repeated
// squaring, kept per joint for the last periods seen). The result is the
// same sub-step recursion, not an approximation of it: it differs from the
// loop only by rounding.
//
// Whether the period is linear is proven before the step is taken, from the
// (v, ∫e_v) part of A: its state relaxes to the fixed point y* = (u, B·u/Ki)
// (v, ∫e_v) part of A: its state relaxes to the fixed point
// y* = (u, (B·u + c)/Ki) as w·A^i·(y_0 − y*), a sum of powers of two
// eigenvalues of modulus below 1, so |w·A^i·d| has a bound over every
// sub-step i that costs a few operations. The step is linear when
//   - the drive's acceleration stays inside ±max_accel over every sub-step
//     (|B·u + c| + the bound of the PI output's transient < max_accel), and
//   - with Coulomb friction or backlash, the motor's velocity keeps one
//     sign over the period (it moves already, towards u, and |u| > the
//     bound of the velocity's transient): friction is then the constant c,
//     and the play operator on a monotone motion is the play operator of
//     its end point.
// Otherwise (the limit possibly reached, a possible stop or reversal with
// friction or backlash, an unstable or degenerate sub-step) servo_step
// takes its sub-steps one by one.
#pragma once

#include <array>

namespace truecut::sim {

struct ServoParams;
struct ServoState;

// A^N and b's sum for one period and one set of drive gains.
struct ServoPeriodMap {
  double period_s = 0.0;  // key: the period and the gains it was made for
  double vel_kp_per_s = 0.0;
  double vel_ki_per_s2 = 0.0;
  double viscous_per_s = 0.0;
  bool usable = false;  // false: the sub-step is unstable or its modes degenerate
  double m[3][5] = {};  // x_N = m[:, 0..2] · x_0 + m[:, 3] · u + m[:, 4] · c
  // The one-sub-step (v, ∫e_v) matrix [[a11, a12], [a21, 1]] and its
  // eigenvalues: complex re ± i·im (im > 0), or real l1 > l2 (im == 0).
  double a11 = 0.0, a12 = 0.0, a21 = 0.0;
  double re = 0.0, im = 0.0, l1 = 0.0, l2 = 0.0;
};

// The maps of the last periods a joint was stepped with (a recording's
// intervals take a few distinct values; a servo loop one).
struct ServoLinearCache {
  std::array<ServoPeriodMap, 4> maps{};
  unsigned next = 0;  // the entry replaced next
};

// Advances `s` over one period of `period_s` with velocity reference
// `v_ref` as servo_step's sub-steps would, when they are provably linear
// over the period (above), and returns true; returns false with `s`
// unchanged otherwise. `n` is servo_substeps(period_s).
bool servo_linear_step(const ServoParams& p, ServoState& s, double v_ref, double period_s, int n,
                       ServoLinearCache& cache) noexcept;

}  // namespace truecut::sim
