// ISO 230-4 from a recording: circles with planted radius error, ellipse,
// backlash, reversal spike and servo mismatch.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <numbers>
#include <random>

#include "test_paths.hpp"
#include "truecut/analysis/iso230_circular.hpp"

namespace truecut::analysis {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kR = 100, kCx = 50, kCy = -20;

// measured(θ, direction, t, &x, &y) turns the commanded point into the
// measured one. Each direction is one full circle of 3600 samples at 1 kHz,
// with a straight feed-in and a standstill before it.
using Distort = std::function<void(double theta, int dir, double& x, double& y)>;

Recording circle_recording(const Distort& distort, bool ccw, bool cw, std::uint32_t seed = 4,
                           double noise_mm = 0.0002) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_mm);
  Recording rec;
  rec.file = "planted.csv";
  auto& xc = rec.channels["x_cmd"];
  auto& yc = rec.channels["y_cmd"];
  auto& xm = rec.channels["x_meas"];
  auto& ya = rec.channels["y_act"];
  double t = 0;
  auto add = [&](double x, double y, double mx, double my) {
    rec.t_s.push_back(t);
    t += 0.001;
    xc.push_back(x), yc.push_back(y), xm.push_back(mx + noise(rng)), ya.push_back(my + noise(rng));
  };
  for (int k = 0; k <= 100; ++k)
    add(kCx + kR * k / 100.0, kCy, kCx + kR * k / 100.0, kCy);  // feed-in
  for (int dir : {+1, -1}) {
    if ((dir > 0 && !ccw) || (dir < 0 && !cw)) continue;
    for (int k = 0; k < 50; ++k)
      add(kCx + kR, kCy, kCx + kR, kCy);
    for (int k = 1; k <= 3600; ++k) {
      const double th = dir * k * 2 * kPi / 3600;
      double x = kCx + kR * std::cos(th), y = kCy + kR * std::sin(th);
      double mx = x, my = y;
      distort(std::remainder(th, 2 * kPi), dir, mx, my);
      add(x, y, mx, my);
    }
  }
  return rec;
}

// Radial shape around the true centre: r = R + a0 + c2·cos(2(θ − φ)).
Distort polar_shape(double a0, double c2, double phi_deg) {
  return [=](double th, int, double& x, double& y) {
    const double r = kR + a0 + c2 * std::cos(2 * (th - phi_deg * kPi / 180));
    x = kCx + r * std::cos(th);
    y = kCy + r * std::sin(th);
  };
}

const CircleHint* hint(const CircularTest& c, const std::string& effect) {
  for (const auto& h : c.hints)
    if (h.effect == effect) return &h;
  return nullptr;
}

TEST(Iso230Circular, PlantedRadiusErrorAndSquarenessEllipse) {
  const double a0 = 0.005, c2 = 0.004;
  auto rec = circle_recording(polar_shape(a0, c2, 45), true, true);
  CircleOptions o;
  o.radius_mm = kR;
  auto c = evaluate_circle(rec, o);
  EXPECT_EQ(c.measured_p, "x_meas");
  EXPECT_EQ(c.measured_q, "y_act");
  ASSERT_EQ(c.runs.size(), 2u);
  EXPECT_EQ(c.runs[0].direction, "ccw");
  EXPECT_NEAR(c.runs[0].swept_deg, 360, 0.2);
  EXPECT_NEAR(c.nominal_centre_p_mm, kCx, 1e-9);
  EXPECT_NEAR(c.runs[0].centre_p_mm, kCx, 2e-5);
  // G = 2·c2 plus the noise extremes; F = a0 ± c2.
  EXPECT_NEAR(c.G_mm, 2 * c2, 0.0015);
  EXPECT_GT(c.G_mm, 2 * c2);
  EXPECT_NEAR(c.F_max_mm, a0 + c2, 0.0008);
  EXPECT_NEAR(c.F_min_mm, a0 - c2, 0.0008);
  EXPECT_NEAR(c.F_mm, a0 + c2, 0.0008);
  ASSERT_TRUE(c.H_mm);
  EXPECT_LT(*c.H_mm, 0.0015);  // the same path both ways: only noise
  ASSERT_GE(c.harmonics.size(), 3u);
  EXPECT_NEAR(c.harmonics[0].amplitude_mm, a0, 2e-5);
  EXPECT_NEAR(c.harmonics[2].amplitude_mm, c2, 2e-5);
  EXPECT_NEAR(c.harmonics[2].phase_deg, 45, 0.5);
  EXPECT_NEAR(c.harmonics[1].amplitude_mm, 0, 2e-5);
  EXPECT_NEAR(c.harmonics[3].amplitude_mm, 0, 2e-5);
  const auto* sq = hint(c, "squareness");
  ASSERT_NE(sq, nullptr);
  EXPECT_NEAR(sq->value, 2 * c2 / kR * 1e6, 1.0);  // µrad
  EXPECT_NE(hint(c, "radius_offset"), nullptr);
  EXPECT_EQ(hint(c, "scale_mismatch"), nullptr);
  EXPECT_EQ(hint(c, "servo_mismatch"), nullptr);
  EXPECT_EQ(hint(c, "backlash"), nullptr);
}

TEST(Iso230Circular, EllipseAlongAnAxisIsScaleMismatch) {
  auto rec = circle_recording(polar_shape(0, 0.003, 90), true, false);
  auto c = evaluate_circle(rec, {});
  EXPECT_NEAR(c.nominal_radius_mm, kR, 1e-9);  // fitted to the command
  EXPECT_FALSE(c.H_mm);
  EXPECT_NEAR(c.harmonics[2].phase_deg, 90, 0.5);
  const auto* s = hint(c, "scale_mismatch");
  ASSERT_NE(s, nullptr);
  EXPECT_EQ(s->axis, "y");
  EXPECT_EQ(hint(c, "squareness"), nullptr);
  EXPECT_EQ(hint(c, "radius_offset"), nullptr);
}

TEST(Iso230Circular, BacklashOnXGivesHysteresisAndSteps) {
  const double lost_motion = 0.004;
  // x stays behind the command by half the lost motion in its direction of travel.
  auto rec = circle_recording(
      [&](double th, int dir, double& x, double&) {
        const double vx = -dir * std::sin(th);
        if (std::abs(vx) > 1e-12) x -= std::copysign(lost_motion / 2, vx);
      },
      true, true);
  auto c = evaluate_circle(rec, {});
  ASSERT_TRUE(c.H_mm);
  EXPECT_NEAR(*c.H_mm, lost_motion, 0.0012);
  const auto* b = hint(c, "backlash");
  ASSERT_NE(b, nullptr) << (c.hints.empty() ? "" : c.hints[0].text);
  EXPECT_EQ(b->axis, "x");
  EXPECT_NEAR(b->value, lost_motion * 1e3, 1.2);
  EXPECT_EQ(hint(c, "reversal_spike"), nullptr);
  EXPECT_EQ(hint(c, "squareness"), nullptr);
}

TEST(Iso230Circular, ReversalSpikeOnY) {
  const double height = 0.006;
  // Right after y reverses (90°, 270°) the path bulges outwards for a few degrees.
  auto rec = circle_recording(
      [&](double th, int dir, double& x, double& y) {
        for (double q : {kPi / 2, -kPi / 2}) {
          const double past = dir * std::remainder(th - q, 2 * kPi) * 180 / kPi;
          if (past > 0 && past < 8) {
            const double bump = height * std::exp(-past / 1.5);
            x += bump * std::cos(th);
            y += bump * std::sin(th);
          }
        }
      },
      true, true);
  auto c = evaluate_circle(rec, {});
  const auto* s = hint(c, "reversal_spike");
  ASSERT_NE(s, nullptr);
  EXPECT_EQ(s->axis, "y");
  EXPECT_NEAR(s->value, height * 1e3, 1.5);
  EXPECT_EQ(hint(c, "backlash"), nullptr);
}

TEST(Iso230Circular, ServoMismatchTurnsOverWithDirection) {
  // x follows the command 0.2 ms later than y.
  const double lag_s = 0.0002, omega = 2 * kPi / 3.6;  // rad/s: one circle in 3.6 s
  auto rec = circle_recording([&](double th, int dir, double& x,
                                  double&) { x = kCx + kR * std::cos(th - dir * omega * lag_s); },
                              true, true);
  auto c = evaluate_circle(rec, {});
  const auto* s = hint(c, "servo_mismatch");
  ASSERT_NE(s, nullptr);
  EXPECT_EQ(s->axis, "x");
  EXPECT_NEAR(s->value, lag_s * 1e3, 0.02);
  EXPECT_EQ(hint(c, "squareness"), nullptr);
}

TEST(Iso230Circular, NoCircleIsAnError) {
  Recording rec;
  rec.file = "line.csv";
  for (int k = 0; k < 100; ++k) {
    rec.t_s.push_back(k);
    rec.channels["x_cmd"].push_back(k);
    rec.channels["x_act"].push_back(k);
    rec.channels["y_cmd"].push_back(0);
    rec.channels["y_act"].push_back(0);
  }
  EXPECT_THROW(evaluate_circle(rec, {}), RecordingError);
  rec.channels.erase("y_act");
  EXPECT_THROW(evaluate_circle(rec, {}), RecordingError);
}

}  // namespace
}  // namespace truecut::analysis
