// The servo period taken as one linear step (servo_linear_step.hpp) against
// the sub-steps taken one by one: the same state within rounding over a
// sweep of drives, periods and motions; refused wherever the sub-steps leave
// the linear regime (the acceleration limit reached, Coulomb friction, a
// reversal inside the period with backlash), with the limit's peak found by
// the test's own sub-step loop.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "truecut/sim/servo_linear_step.hpp"
#include "truecut/sim/servo_model.hpp"

using namespace truecut::sim;

namespace {

// The drive's velocity reference for a period, as the servo model forms it
// (docs/machine-model.md): v_ref = ff1·Δcmd/T + kv·(cmd − encoder).
double velocity_reference(const ServoParams& p, const ServoState& s, double cmd, double period_s) {
  return p.ff1 * (cmd - s.prev_cmd) / period_s + p.kv_per_s * (cmd - encoder_reading(p, s.pos));
}

// The largest |PI output| and the velocity's extremes over the period's
// sub-steps, from the equations of docs/machine-model.md without the limit
// and without friction's stop at zero (the test's own loop).
struct Excursion {
  double peak_accel = 0.0, min_vel = INFINITY, max_vel = -INFINITY;
};
Excursion unlimited_excursion(const ServoParams& p, ServoState s, double v_ref, double period_s) {
  const int n = servo_substeps(period_s);
  const double h = period_s / n;
  Excursion e;
  e.min_vel = e.max_vel = s.vel;
  for (int i = 0; i < n; ++i) {
    const double a_pi = p.vel_kp_per_s * (v_ref - s.vel) + p.vel_ki_per_s2 * s.vel_integral;
    e.peak_accel = std::max(e.peak_accel, std::abs(a_pi));
    s.vel_integral += h * (v_ref - s.vel);
    const double friction = s.vel > 0.0 ? p.coulomb_accel : s.vel < 0.0 ? -p.coulomb_accel : 0.0;
    s.vel += h * (a_pi - friction - p.viscous_per_s * s.vel);
    e.min_vel = std::min(e.min_vel, s.vel);
    e.max_vel = std::max(e.max_vel, s.vel);
  }
  return e;
}

// The sub-steps one by one from `s` with velocity reference `v_ref`: a
// command giving exactly v_ref (from a state at position 0) on a drive
// without feedforward or encoder steps; prev_cmd left as it was.
ServoState substeps_from(const ServoParams& p, ServoState s, double v_ref, double period_s) {
  ServoParams q = p;
  q.ff1 = 0.0, q.encoder_resolution = 0.0, q.kv_per_s = 1.0;
  const double prev_cmd = s.prev_cmd;
  servo_step(q, s, s.pos + v_ref, period_s);
  s.prev_cmd = prev_cmd;
  return s;
}

double scale_of(const ServoState& s) {
  return 1.0 + std::abs(s.pos) + std::abs(s.vel) * 1e-3 + std::abs(s.vel_integral) * 1e3;
}

void expect_same_state(const ServoState& a, const ServoState& b, const std::string& where) {
  const double tol = 1e-9 * std::max(scale_of(a), scale_of(b));
  EXPECT_NEAR(a.pos, b.pos, tol) << where;
  EXPECT_NEAR(a.table, b.table, tol) << where;
  EXPECT_NEAR(a.vel, b.vel, 1e3 * tol) << where;
  EXPECT_NEAR(a.vel_integral, b.vel_integral, 1e-3 * tol) << where;
  EXPECT_EQ(a.prev_cmd, b.prev_cmd) << where;
}

ServoParams random_drive(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  ServoParams p;
  p.kv_per_s = 5.0 + 195.0 * u(rng);
  p.ff1 = u(rng) < 0.3 ? 0.0 : u(rng);
  p.vel_kp_per_s = 2.0 * M_PI * (5.0 + 495.0 * u(rng));  // 5 Hz to 500 Hz
  p.vel_ki_per_s2 = p.vel_kp_per_s / (1e-3 + 49e-3 * u(rng));
  p.viscous_per_s = u(rng) < 0.5 ? 0.0 : 50.0 * u(rng);
  p.max_accel = std::pow(10.0, 2.0 + 3.0 * u(rng));  // 100 to 1e5 mm/s²
  p.backlash_play = u(rng) < 0.5 ? 0.0 : 0.05 * u(rng);
  p.coulomb_accel = u(rng) < 0.5 ? 0.0 : 200.0 * u(rng);
  p.encoder_resolution = u(rng) < 0.5 ? 0.0 : 1e-4;
  return p;
}

}  // namespace

// Random drives, periods from 125 µs to 0.1 s (the 10 ms servo of a
// recording diagnosed at 100 ms), motions with ramps, steps and reversals:
// the state after every period is the sub-steps' within rounding, and most
// periods are taken as one step.
TEST(ServoLinearStep, MatchesTheSubStepsOverASweepOfDrivesAndMotions) {
  std::mt19937_64 rng(20261201);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double periods[] = {125e-6, 1e-3, 2.5e-3, 1e-2, 0.1};
  long linear = 0, total = 0;
  for (int c = 0; c < 400; ++c) {
    ServoParams p = random_drive(rng);
    const double period = periods[c % 5];
    // A position loop sampled every T is stable for kv·T well below 1: an
    // unstable one amplifies rounding itself, whatever computes it.
    p.kv_per_s = std::min(p.kv_per_s, 0.3 / period);
    ServoState slow = servo_start(10.0 * u(rng)), fast = slow;
    ServoLinearCache cache;
    const double speed = 200.0 * u(rng);     // mm/s
    const double reverse_s = 0.05 + u(rng);  // a reversal every so often
    const int cycles = std::min(300, int(std::ceil(2.0 / period)));
    for (int k = 1; k <= cycles; ++k) {
      const double t = k * period;
      double cmd = slow.prev_cmd;
      if (k % 97 == 0)
        cmd += 0.5 * (u(rng) - 0.5);  // a step: the limit reached, on many drives
      else
        cmd += (std::fmod(t, 2.0 * reverse_s) < reverse_s ? 1.0 : -1.0) * speed * period;
      const double v_ref = velocity_reference(p, fast, cmd, period);
      servo_step(p, slow, cmd, period);
      ServoState probe = fast;
      const bool was_linear =
          servo_linear_step(p, probe, v_ref, period, servo_substeps(period), cache);
      servo_step(p, fast, cmd, period, cache);
      linear += was_linear;
      ++total;
      expect_same_state(slow, fast,
                        "case " + std::to_string(c) + " period " + std::to_string(period) +
                            " cycle " + std::to_string(k));
      if (::testing::Test::HasFailure()) return;
    }
  }
  // Steps, reversals against backlash and low limits refuse some periods.
  std::printf("%ld of %ld periods taken as one step\n", linear, total);
  EXPECT_GT(linear, 0);
}

// What makes the diagnosis fast: ordinary motion, its PI output well inside
// the limit, is linear in every period — on the drive's defaults at a 1 ms
// servo and at the 10 ms of a recording diagnosed every 100 ms, for a
// cosine from rest (peak acceleration 10 % of the limit) and a ramp with dwells.
TEST(ServoLinearStep, OrdinaryMotionIsLinearInEveryPeriod) {
  for (const double period : {1e-3, 1e-2}) {
    for (const int variant : {0, 1, 2}) {  // plain, backlash, Coulomb friction
      const bool backlash = variant == 1, friction = variant == 2;
      ServoParams p;  // the defaults: 40 Hz velocity loop, 5000 mm/s² limit
      p.kv_per_s = 30.0;
      p.ff1 = 0.5;
      p.backlash_play = backlash ? 0.01 : 0.0;
      p.coulomb_accel = friction ? 100.0 : 0.0;
      ServoState s = servo_start(0.0);
      ServoLinearCache cache;
      const double omega = 2.0 * M_PI * 0.5, amp = 0.1 * p.max_accel / (omega * omega);
      int refused = 0, moving = 0;
      const int cycles = int(std::lround(4.0 / period));
      for (int k = 1; k <= cycles; ++k) {
        const double cmd = amp * (1.0 - std::cos(omega * k * period));  // from rest
        const double v_ref = velocity_reference(p, s, cmd, period);
        ServoState probe = s;
        const bool linear =
            servo_linear_step(p, probe, v_ref, period, servo_substeps(period), cache);
        // With backlash or friction a period near a reversal of the motor
        // (which lags the command's crests; below 10 mm/s, 6 % of the peak
        // speed) is not taken as one step where its velocity could cross
        // zero.
        const bool near_crest = std::abs(s.vel) < 10.0;
        if (!((backlash || friction) && near_crest)) {
          ++moving;
          refused += !linear;
        }
        servo_step(p, s, cmd, period, cache);
      }
      EXPECT_EQ(0, refused) << "period " << period << ", variant " << variant << ": " << refused
                            << " of " << moving << " refused";
    }
  }
}

// Right at the acceleration limit: with the limit just below the period's
// peak PI output the step is refused (the sub-steps clip), just above it
// the step may be taken and then matches.
TEST(ServoLinearStep, RefusedWhereTheAccelerationLimitIsReached) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int taken_above = 0;
  for (int c = 0; c < 300; ++c) {
    ServoParams p = random_drive(rng);
    p.backlash_play = 0.0;
    const double period = c % 2 ? 1e-3 : 1e-2;
    ServoState s = servo_start(0.0);
    s.vel = 100.0 * (u(rng) - 0.5);
    s.vel_integral = 1e-3 * (u(rng) - 0.5);
    const double v_ref = 200.0 * (u(rng) - 0.5);
    const double peak = unlimited_excursion(p, s, v_ref, period).peak_accel;
    ServoLinearCache cache;
    p.max_accel = peak * (1.0 - 1e-6);
    ServoState below = s;
    EXPECT_FALSE(servo_linear_step(p, below, v_ref, period, servo_substeps(period), cache))
        << "case " << c << ": the sub-steps reach the limit " << p.max_accel;
    p.max_accel = peak * 1.05;
    ServoState above = s;
    if (servo_linear_step(p, above, v_ref, period, servo_substeps(period), cache)) {
      ++taken_above;
      expect_same_state(substeps_from(p, s, v_ref, period), above, "case " + std::to_string(c));
    }
  }
  EXPECT_GT(taken_above, 150) << "the bound of the transient is not far above its peak";
}

// With backlash the play operator is applied to the period's end only when
// the motor provably keeps its direction: a period whose velocity changes
// sign is refused, and any period taken matches the sub-steps.
TEST(ServoLinearStep, WithBacklashOnlyPeriodsThatKeepTheirDirection) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int reversing = 0;
  for (int c = 0; c < 400; ++c) {
    ServoParams p = random_drive(rng);
    p.backlash_play = 0.01 + 0.04 * u(rng);
    p.max_accel = 1e9;
    p.encoder_resolution = 0.0;
    const double period = c % 2 ? 1e-3 : 1e-2;
    ServoState s = servo_start(0.0);
    s.vel = 50.0 * (u(rng) - 0.5);
    s.table = s.pos + p.backlash_play * (u(rng) - 0.5);
    const double v_ref = 50.0 * (u(rng) - 0.5);
    const Excursion e = unlimited_excursion(p, s, v_ref, period);
    const bool reverses = e.min_vel < 0.0 && e.max_vel > 0.0;
    reversing += reverses;
    ServoLinearCache cache;
    ServoState fast = s;
    const bool taken = servo_linear_step(p, fast, v_ref, period, servo_substeps(period), cache);
    if (reverses) {
      EXPECT_FALSE(taken) << "case " << c << ": the motor reverses in the period";
    }
    if (taken)
      expect_same_state(substeps_from(p, s, v_ref, period), fast, "case " + std::to_string(c));
  }
  EXPECT_GT(reversing, 20) << "the sweep must contain reversals to show anything";
}

TEST(ServoLinearStep, NotTakenFromStandstillWithFrictionOrForAnUnstableSubStep) {
  ServoParams p;
  ServoState s = servo_start(0.0);
  ServoLinearCache cache;
  p.coulomb_accel = 10.0;
  EXPECT_FALSE(servo_linear_step(p, s, 5.0, 1e-3, servo_substeps(1e-3), cache))
      << "sticking at rest until the drive overcomes the friction";
  ServoState moving = s;
  moving.vel = -5.0;
  EXPECT_FALSE(servo_linear_step(p, moving, 5.0, 1e-3, servo_substeps(1e-3), cache))
      << "moving against the reference: friction changes sign in the period";
  moving.vel = 4.9;
  const ServoState ref = substeps_from(p, moving, 5.0, 1e-3);
  EXPECT_TRUE(servo_linear_step(p, moving, 5.0, 1e-3, servo_substeps(1e-3), cache));
  expect_same_state(ref, moving, "moving with friction");
  p.coulomb_accel = 0.0;
  EXPECT_TRUE(servo_linear_step(p, s, 5.0, 1e-3, servo_substeps(1e-3), cache));
  // A velocity loop far beyond the sub-step's reach (Kp·h = 25): the
  // sub-steps diverge, and so must the one step's refusal hold.
  ServoParams wild = p;
  wild.vel_kp_per_s = 1e6;
  ServoState w = servo_start(0.0);
  EXPECT_FALSE(servo_linear_step(wild, w, 5.0, 1e-3, servo_substeps(1e-3), cache));
  // No integral action: no fixed point to relax to.
  ServoParams p_only = p;
  p_only.vel_ki_per_s2 = 0.0;
  EXPECT_FALSE(servo_linear_step(p_only, w, 5.0, 1e-3, servo_substeps(1e-3), cache));
}
