// Each effect switched on alone gives its textbook signature; with every
// effect off the machine is ideal; runs are bit-for-bit repeatable.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <random>

#include "machine_fixtures.hpp"

using namespace truecut::sim;
using namespace truecut::sim::test;

namespace {

constexpr double kPi = std::numbers::pi;

// Seeded random smooth path on every joint: a sum of sines.
MachineInputs random_path(double t, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> amp(1.0, 50.0), freq(0.1, 2.0), ph(0.0, 2 * kPi);
  MachineInputs in;
  for (int j = 0; j < kJointCount; ++j)
    for (int h = 0; h < 3; ++h)
      in.pos_cmd[j] += amp(rng) * std::sin(2 * kPi * freq(rng) * t + ph(rng));
  in.spindle_power_kw = 5.0 + 5.0 * std::sin(t);
  return in;
}

MachineParams everything_on() {
  MachineParams m = ideal_params();
  for (int j = 0; j < kJointCount; ++j) {
    enable_servo_lag(m, j, 30.0, 0.5);
    m.joints[j].drive.encoder_resolution = 1e-4;
  }
  auto& fx = m.effects;
  fx.backlash.enabled = fx.reversal_spike.enabled = fx.pitch_error.enabled = true;
  fx.thermal_drift.enabled = fx.squareness.enabled = fx.straightness.enabled = true;
  for (int j = 0; j < kJointCount; ++j) {
    fx.backlash.axes[j] = BacklashAxis{0.005};
    fx.reversal_spike.axes[j] = ReversalSpikeAxis{50.0, 0.01};
  }
  for (int j = 0; j < 3; ++j) {
    fx.pitch_error.axes[j] = PitchErrorAxis{10.0, 0.0, 2.0, 5.0, 30.0};
    fx.thermal_drift.axes[j] = ThermalDriftAxis{0.01, 5.0, ThermalDriver::kSpindlePower, 10.0};
  }
  fx.squareness.params = {20.0, -10.0, 5.0};
  fx.straightness.params.components[kEYX] = StraightnessComponent{30.0, 5.0, 0.0};
  return m;
}

}  // namespace

TEST(Ideal, ActualEqualsCommandedExactly) {
  MachineParams m = ideal_params();
  // Parameters present but switched off change nothing.
  MachineParams off = everything_on();
  off.effects.servo_lag.enabled = off.effects.backlash.enabled = false;
  off.effects.reversal_spike.enabled = off.effects.pitch_error.enabled = false;
  off.effects.thermal_drift.enabled = off.effects.squareness.enabled = false;
  off.effects.straightness.enabled = false;
  for (const auto& params : {m, off}) {
    auto tr = run(params, 1e-3, 2000, [](double t) { return random_path(t, 7); });
    for (size_t k = 0; k < tr.out.size(); ++k) {
      for (int j = 0; j < kJointCount; ++j) {
        ASSERT_EQ(tr.in[k].pos_cmd[j], tr.out[k].pos_act[j]) << "cycle " << k << " joint " << j;
        ASSERT_EQ(tr.in[k].pos_cmd[j], tr.out[k].pos_true[j]);
        ASSERT_EQ(0.0, tr.out[k].f_error[j]);
      }
      for (int i = 0; i < 3; ++i)
        ASSERT_EQ(tr.in[k].pos_cmd[i], tr.out[k].xyz_true[i]);
    }
  }
}

TEST(Determinism, TwoRunsAreBitIdentical) {
  const MachineParams m = everything_on();
  auto a = run(m, 250e-6, 8000, [](double t) { return random_path(t, 11); });
  auto b = run(m, 250e-6, 8000, [](double t) { return random_path(t, 11); });
  ASSERT_EQ(a.out.size(), b.out.size());
  for (size_t k = 0; k < a.out.size(); ++k)
    ASSERT_TRUE(bitwise_equal(a.out[k], b.out[k])) << "cycle " << k;
  // And the effects did something.
  double dev = 0.0;
  for (size_t k = 0; k < a.out.size(); ++k)
    dev = std::max(dev, std::abs(a.out[k].xyz_true[0] - a.in[k].pos_cmd[kX]));
  EXPECT_GT(dev, 1e-3);
}

TEST(Backlash, StepOfThePlayAtEachReversal) {
  for (int joint : {int(kX), int(kC)}) {
    MachineParams m = ideal_params();
    const double b = 0.02;
    m.effects.backlash.enabled = true;
    m.effects.backlash.axes[joint] = BacklashAxis{b};
    // Triangle 0 → 10 → 0 → 10 at 10 units/s.
    auto tri = [&](double t) {
      MachineInputs in;
      const double ph = std::fmod(t, 2.0);
      in.pos_cmd[joint] = ph < 1.0 ? 10.0 * ph : 10.0 * (2.0 - ph);
      return in;
    };
    auto tr = run(m, 1e-3, 3500, tri);
    for (size_t k = 0; k < tr.out.size(); ++k) {
      const double t = tr.t[k], cmd = tr.in[k].pos_cmd[joint];
      ASSERT_EQ(cmd, tr.out[k].pos_act[joint]) << "the motor-side encoder never sees the play";
      const double err = tr.out[k].pos_true[joint] - cmd;
      const double ph = std::fmod(t, 2.0);
      if (t > 0.1 && ph > 0.05 && ph < 0.95) {
        EXPECT_NEAR(-b / 2, err, 1e-12) << "t=" << t;
      }
      if (ph > 1.05 && ph < 1.95) {
        EXPECT_NEAR(+b / 2, err, 1e-12) << "t=" << t;
      }
    }
  }
}

TEST(Backlash, SemiClosedLoopDoesNotFeelIt) {
  MachineParams m = ideal_params();
  enable_servo_lag(m, kX, 30.0);
  MachineParams with = m;
  with.effects.backlash.enabled = true;
  with.effects.backlash.axes[kX] = BacklashAxis{0.05};
  auto path = [](double t) { return on_x(20.0 * std::sin(2 * kPi * 0.5 * t)); };
  auto a = run(m, 1e-3, 4000, path), b = run(with, 1e-3, 4000, path);
  double table_lag = 0.0;
  // The motor's motion is the same computation with and without the play;
  // only near a reversal it runs sub-step by sub-step instead of as one
  // linear step (servo_linear_step.hpp), so the two agree to rounding
  // (a play felt by the loop would show at the 0.05 mm of the gap).
  for (size_t k = 0; k < a.out.size(); ++k) {
    ASSERT_NEAR(a.out[k].f_error[kX], b.out[k].f_error[kX], 1e-12);
    table_lag = std::max(table_lag, std::abs(b.out[k].pos_true[kX] - a.out[k].pos_true[kX]));
  }
  EXPECT_NEAR(0.025, table_lag, 1e-9);
}

namespace {

// Following error of x on a sine with Coulomb friction `coulomb_n`.
std::vector<double> sine_following_error(double coulomb_n) {
  MachineParams m = ideal_params();
  enable_servo_lag(m, kX, 30.0, 1.0);
  m.joints[kX].drive.inertia = 400.0;
  if (coulomb_n > 0.0) {
    m.effects.reversal_spike.enabled = true;
    m.effects.reversal_spike.axes[kX] = ReversalSpikeAxis{coulomb_n, 0.0};
  }
  // 20 mm amplitude at 0.5 Hz: reversals at t = 1.5 s, 2.5 s, ...
  auto tr = run(m, 1e-3, 3000,
                [](double t) { return on_x(20.0 * std::sin(2 * kPi * 0.5 * t + 0.5 * kPi)); });
  std::vector<double> fe;
  for (const auto& o : tr.out)
    fe.push_back(o.f_error[kX]);
  return fe;
}

}  // namespace

TEST(ReversalSpike, SpikeAtReversalGrowsWithCoulombFriction) {
  // cos starts at the top: reversals at t = 1 s and 2 s.
  const auto base = sine_following_error(0.0);
  double previous = 0.0;
  for (double fc : {30.0, 100.0, 300.0}) {
    const auto fe = sine_following_error(fc);
    double peak = 0.0, peak_t = 0.0, mid = 0.0;
    for (size_t k = 0; k < fe.size(); ++k) {
      const double t = k * 1e-3, d = std::abs(fe[k] - base[k]);
      if (t > 1.9 && t < 2.3 && d > peak) peak = d, peak_t = t;
      if (t > 2.4 && t < 2.6) mid = std::max(mid, d);  // full speed, mid-stroke
    }
    EXPECT_GT(peak, 1e-4) << "Fc=" << fc;
    EXPECT_GT(peak, 1.5 * previous) << "Fc=" << fc << " must raise the spike";
    EXPECT_GE(peak_t, 2.0) << "the spike follows the reversal";
    EXPECT_LT(peak_t, 2.1);
    EXPECT_LT(mid, 0.1 * peak) << "Fc=" << fc << ": away from the reversal the loop compensates";
    previous = peak;
  }
  // Without friction the error near the reversal is smooth (the lag of the
  // acceleration), with friction it has a sharp peak: compare each sample with
  // the mean of its neighbours 40 ms away.
  auto sharpness = [](const std::vector<double>& fe) {
    double worst = 0.0;
    for (size_t k = 1900; k < 2300; ++k)
      worst = std::max(worst, std::abs(fe[k] - 0.5 * (fe[k - 40] + fe[k + 40])));
    return worst;
  };
  const double smooth = sharpness(base), spiky = sharpness(sine_following_error(30.0));
  EXPECT_GT(spiky, 1e-3);
  EXPECT_LT(smooth, 0.05 * spiky);
}

TEST(PitchError, ErrorVersusPositionIsLinearPlusSine) {
  MachineParams m = ideal_params();
  const double k_um_m = 15.0, ref = 50.0, amp_um = 3.0, period_mm = 10.0, phase_deg = 30.0;
  m.effects.pitch_error.enabled = true;
  m.effects.pitch_error.axes[kY] = PitchErrorAxis{k_um_m, ref, amp_um, period_mm, phase_deg};
  auto tr = run(m, 1e-3, 8000, [](double t) {
    MachineInputs in;
    in.pos_cmd[kY] = -200.0 + 50.0 * t;
    return in;
  });
  // Least squares of the error on [p − ref, sin(2πp/P), cos(2πp/P)].
  double A[3][3] = {}, r[3] = {};
  for (size_t k = 0; k < tr.out.size(); ++k) {
    const double p = tr.in[k].pos_cmd[kY];
    ASSERT_EQ(p, tr.out[k].pos_act[kY]);
    const double e = tr.out[k].pos_true[kY] - p;
    const double x[3] = {p - ref, std::sin(2 * kPi * p / period_mm),
                         std::cos(2 * kPi * p / period_mm)};
    for (int i = 0; i < 3; ++i) {
      r[i] += x[i] * e;
      for (int l = 0; l < 3; ++l)
        A[i][l] += x[i] * x[l];
    }
  }
  // Solve by Gaussian elimination (3×3).
  for (int c = 0; c < 3; ++c)
    for (int i = c + 1; i < 3; ++i) {
      const double f = A[i][c] / A[c][c];
      for (int l = c; l < 3; ++l)
        A[i][l] -= f * A[c][l];
      r[i] -= f * r[c];
    }
  double sol[3];
  for (int i = 2; i >= 0; --i) {
    double s = r[i];
    for (int l = i + 1; l < 3; ++l)
      s -= A[i][l] * sol[l];
    sol[i] = s / A[i][i];
  }
  EXPECT_NEAR(k_um_m, sol[0] * 1e6, 1e-6);
  EXPECT_NEAR(amp_um, std::hypot(sol[1], sol[2]) * 1e3, 1e-6);
  EXPECT_NEAR(phase_deg, std::atan2(sol[2], sol[1]) * 180.0 / kPi, 1e-6);
}

namespace {

// Fits δ(t) = g·(1 − e^(−t/τ)): g by linear least squares for each τ,
// τ by golden-section search on the residual.
std::pair<double, double> fit_first_order(const std::vector<double>& t,
                                          const std::vector<double>& d) {
  auto g_and_sse = [&](double tau) {
    double sxx = 0, sxy = 0;
    for (size_t i = 0; i < t.size(); ++i) {
      const double x = -std::expm1(-t[i] / tau);
      sxx += x * x;
      sxy += x * d[i];
    }
    const double g = sxy / sxx;
    double sse = 0;
    for (size_t i = 0; i < t.size(); ++i) {
      const double r = d[i] - g * -std::expm1(-t[i] / tau);
      sse += r * r;
    }
    return std::pair{g, sse};
  };
  double lo = 1.0, hi = 200.0;
  const double phi = (std::sqrt(5.0) - 1) / 2;
  for (int it = 0; it < 200; ++it) {
    const double a = hi - phi * (hi - lo), b = lo + phi * (hi - lo);
    if (g_and_sse(a).second < g_and_sse(b).second)
      hi = b;
    else
      lo = a;
  }
  const double tau = 0.5 * (lo + hi);
  return {g_and_sse(tau).first, tau};
}

}  // namespace

TEST(ThermalDrift, TimeDrivenStepResponseHasTheSetTimeConstant) {
  MachineParams m = ideal_params();
  m.effects.thermal_drift.enabled = true;
  m.effects.thermal_drift.axes[kZ] = ThermalDriftAxis{0.03, 20.0, ThermalDriver::kTime, 10.0};
  auto tr = run(m, 1e-3, 80000, [](double) { return MachineInputs{}; });
  std::vector<double> t, d;
  for (size_t k = 0; k < tr.out.size(); k += 100) {
    t.push_back(tr.t[k]);
    d.push_back(tr.out[k].pos_true[kZ] - tr.in[k].pos_cmd[kZ]);
    ASSERT_EQ(tr.in[k].pos_cmd[kZ], tr.out[k].pos_act[kZ]);
  }
  EXPECT_EQ(0.0, d[0]) << "cold start";
  auto [g, tau] = fit_first_order(t, d);
  EXPECT_NEAR(0.03, g, 1e-7);
  EXPECT_NEAR(20.0, tau, 1e-4);
  EXPECT_NEAR(0.03 * (1 - std::exp(-1.0)), d[200], 1e-9) << "63 % after one τ";
}

TEST(ThermalDrift, SpindlePowerDrivesTheGrowthAndItCoolsDown) {
  MachineParams m = ideal_params();
  m.effects.thermal_drift.enabled = true;
  m.effects.thermal_drift.axes[kZ] =
      ThermalDriftAxis{-0.04, 10.0, ThermalDriver::kSpindlePower, 8.0};
  auto tr = run(m, 1e-3, 200000, [](double t) {
    MachineInputs in;
    in.spindle_power_kw = t < 100.0 ? 6.0 : 0.0;
    return in;
  });
  // Power on from t = 0 to 100 s, off afterwards.
  const double at_100 = -0.04 * 6.0 / 8.0 * -std::expm1(-100.0 / 10.0);
  EXPECT_NEAR(at_100, tr.out[100000].pos_true[kZ], 1e-12);
  EXPECT_NEAR(at_100 * std::exp(-5.0), tr.out[150000].pos_true[kZ], 1e-12);
}

namespace {

// Amplitude and phase (deg) of the 2θ component of the radial error of a
// circle of radius R about (cx, cy) in the plane of joints (i, k).
std::pair<double, double> two_theta_lobe(const MachineParams& m, int i, int k, double R, double cx,
                                         double cy) {
  const int n = 3600;
  double a2 = 0, b2 = 0;
  MachineModel model(m);
  MachineState st;
  for (int s = 0; s < n; ++s) {
    const double th = 2 * kPi * s / n;
    MachineInputs in;
    in.pos_cmd[i] = cx + R * std::cos(th);
    in.pos_cmd[k] = cy + R * std::sin(th);
    MachineOutputs out;
    model.step(st, in, 1e-3, out);
    const double r = std::hypot(out.xyz_true[i] - cx, out.xyz_true[k] - cy) - R;
    a2 += 2.0 / n * r * std::cos(2 * th);
    b2 += 2.0 / n * r * std::sin(2 * th);
  }
  return {std::hypot(a2, b2), std::atan2(b2, a2) * 180.0 / kPi};
}

}  // namespace

TEST(Squareness, CircleShowsTheTwoThetaLobeAt45Degrees) {
  const double R = 100.0, gamma_urad = 50.0;
  struct Case {
    int i, k;
    double SquarenessParams::*field;
  };
  for (const Case& c :
       {Case{kX, kY, &SquarenessParams::xy_urad}, Case{kY, kZ, &SquarenessParams::yz_urad},
        Case{kX, kZ, &SquarenessParams::zx_urad}}) {
    MachineParams m = ideal_params();
    m.effects.squareness.enabled = true;
    m.effects.squareness.params.*(c.field) = gamma_urad;
    auto [amp, phase] = two_theta_lobe(m, c.i, c.k, R, 150.0, -80.0);
    EXPECT_NEAR(R * gamma_urad * 1e-6 / 2, amp, 1e-3 * R * gamma_urad * 1e-6 / 2);
    // r − R = (Rγ/2)·sin 2θ: phase of the sin term is +90° in atan2(b2, a2),
    // i.e. the maximum at θ = 45°.
    EXPECT_NEAR(90.0, phase, 0.1);
  }
  MachineParams none = ideal_params();
  EXPECT_LT(two_theta_lobe(none, kX, kY, R, 0.0, 0.0).first, 1e-12);
}

TEST(Straightness, BowFollowsThePolynomialOfTheMovingAxis) {
  MachineParams m = ideal_params();
  m.effects.straightness.enabled = true;
  m.effects.straightness.params.components[kEYX] = StraightnessComponent{40.0, 0.0, 0.0};
  m.effects.straightness.params.components[kEXZ] = StraightnessComponent{0.0, 80.0, 100.0};
  auto tr = run(m, 1e-3, 5001, [](double t) {
    MachineInputs in;
    in.pos_cmd[kX] = -250.0 + 100.0 * t;
    in.pos_cmd[kY] = 12.0;
    in.pos_cmd[kZ] = 300.0 - 60.0 * t;
    return in;
  });
  for (size_t k = 0; k < tr.out.size(); ++k) {
    const double x = tr.in[k].pos_cmd[kX], z = tr.in[k].pos_cmd[kZ];
    const double eyx_um = 40.0 * (x / 1000) * (x / 1000);
    const double exz_um = 80.0 * std::pow((z - 100.0) / 1000, 3);
    ASSERT_NEAR(12.0 + eyx_um * 1e-3, tr.out[k].xyz_true[kY], 1e-12);
    ASSERT_NEAR(x + exz_um * 1e-3, tr.out[k].xyz_true[kX], 1e-12);
    ASSERT_EQ(z, tr.out[k].xyz_true[kZ]);
  }
  EXPECT_NEAR(2.5e-3, tr.out.front().xyz_true[kY] - 12.0, 1e-12) << "40 µm/m² at 250 mm";
}

TEST(Faults, NonFiniteCommandIsHeldAndLatched) {
  MachineParams m = ideal_params();
  enable_servo_lag(m, kX, 30.0);
  MachineModel model(m);
  MachineState st;
  MachineOutputs out;
  model.step(st, on_x(1.0), 1e-3, out);
  EXPECT_FALSE(out.fault);
  model.step(st, on_x(std::nan("")), 1e-3, out);
  EXPECT_TRUE(out.fault);
  for (int k = 0; k < 500; ++k)
    model.step(st, on_x(std::numeric_limits<double>::infinity()), 1e-3, out);
  EXPECT_TRUE(out.fault);
  EXPECT_NEAR(1.0, out.pos_act[kX], 1e-9) << "holds the last good command";
  for (int j = 0; j < kJointCount; ++j)
    EXPECT_TRUE(std::isfinite(out.pos_true[j]));
}

TEST(Faults, CommandOutsideTravelLatchesLimitFault) {
  MachineParams m = ideal_params();
  m.joints[kZ].min = -400.0;
  m.joints[kZ].max = 0.0;
  MachineModel model(m);
  MachineState st;
  MachineOutputs out;
  MachineInputs in;
  in.pos_cmd[kZ] = -10.0;
  model.step(st, in, 1e-3, out);
  EXPECT_FALSE(out.limit_fault);
  in.pos_cmd[kZ] = 0.5;
  model.step(st, in, 1e-3, out);
  EXPECT_TRUE(out.limit_fault);
  in.pos_cmd[kZ] = -10.0;
  model.step(st, in, 1e-3, out);
  EXPECT_TRUE(out.limit_fault) << "latched";
}
