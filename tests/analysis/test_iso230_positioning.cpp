// ISO 230-2 from a recording: a hand-computed example and a seeded 5 × 5 × 2
// test checked against an independent computation of the standard's formulas.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <random>

#include "test_paths.hpp"
#include "truecut/analysis/iso230_positioning.hpp"

namespace truecut::analysis {
namespace {

// deviation[target][direction 0 ↑, 1 ↓][run], mm.
using Table = std::vector<std::array<std::vector<double>, 2>>;

// A linear-cycle test: per run, approach the targets upwards from below the
// first one, overrun past the last, come back downwards, overrun below the
// first. Each target dwell lasts 2 s at 10 Hz; the first samples of a dwell
// carry a settling overshoot that must not enter the reading.
std::filesystem::path write_cycle(const std::string& name, const std::vector<double>& targets,
                                  const Table& dev, double overrun_dwell_s, bool with_meas) {
  const double dt = 0.1, speed = 50;  // mm/s
  std::string csv =
      with_meas ? "t,x_cmd,x_act,x_meas,y_cmd,y_act\n" : "t,x_cmd,x_act,y_cmd,y_act\n";
  double t = 0, pos = targets.front() - 5;
  auto sample = [&](double cmd, double deviation) {
    char b[200];
    if (with_meas)
      std::snprintf(b, sizeof b, "%.17g,%.17g,%.17g,%.17g,7,7\n", t, cmd, cmd, cmd + deviation);
    else
      std::snprintf(b, sizeof b, "%.17g,%.17g,%.17g,7,7\n", t, cmd, cmd + deviation);
    csv += b;
    t += dt;
  };
  auto move_to = [&](double to) {
    const int steps = std::max(1, int(std::ceil(std::abs(to - pos) / (speed * dt))));
    for (int k = 1; k <= steps; ++k)
      sample(pos + (to - pos) * k / steps, 0.003);
    pos = to;
  };
  auto dwell = [&](double seconds, double deviation) {
    for (int k = 0; k < int(std::lround(seconds / dt)); ++k)
      sample(pos, deviation + (k < 4 ? 0.01 * (4 - k) : 0.0));
  };
  dwell(1.0, 0);
  const std::size_t runs = dev[0][0].size();
  for (std::size_t run = 0; run < runs; ++run) {
    for (std::size_t i = 0; i < targets.size(); ++i) {
      move_to(targets[i]);
      dwell(2.0, dev[i][0][run]);
    }
    move_to(targets.back() + 5);
    dwell(overrun_dwell_s, 0.02);
    for (std::size_t i = targets.size(); i-- > 0;) {
      move_to(targets[i]);
      dwell(2.0, dev[i][1][run]);
    }
    move_to(targets.front() - 5);
    dwell(overrun_dwell_s, 0.02);
  }
  auto p = test::scratch_dir() / name;
  std::ofstream(p, std::ios::binary) << csv;
  return p;
}

TEST(Iso230Positioning, HandComputedExample) {
  // µm: target 10: ↑ {2,4,6} (x̄ 4, s 2), ↓ {-1,0,1} (x̄ 0, s 1);
  //     target 20: ↑ {5,5,5} (x̄ 5, s 0), ↓ {1,3,5} (x̄ 3, s 2).
  // x̄₁ = 2, B₁ = 4, R₁ = max(4+2+4, 8, 4) = 10; x̄₂ = 4, B₂ = 2, R₂ = max(0+4+2, 0, 8) = 8.
  // E↑ = 1, E↓ = 3, E = 5 − 0 = 5, M = 4 − 2 = 2, R = 10, B = 4, B̄ = 3,
  // A↑ = (4+4) − (4−4) = 8, A↓ = (3+4) − (0−2) = 9, A = 8 − (−2) = 10.
  const double um = 1e-3;
  Table dev = {{{{2 * um, 4 * um, 6 * um}, {-1 * um, 0, 1 * um}}},
               {{{5 * um, 5 * um, 5 * um}, {1 * um, 3 * um, 5 * um}}}};
  auto file = write_cycle("hand.csv", {10, 20}, dev, 0.0, true);
  auto rec = read_recording(file);
  StandstillOptions o;
  auto r = evaluate_positioning(rec, "x", o);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->measured_channel, "x_meas");
  EXPECT_EQ(r->readings, 12u);
  ASSERT_EQ(r->targets.size(), 2u);
  const double tol = 1e-9;
  EXPECT_NEAR(r->targets[0].target, 10, tol);
  EXPECT_NEAR(r->targets[0].up->mean, 4 * um, tol);
  EXPECT_NEAR(r->targets[0].up->s, 2 * um, tol);
  EXPECT_NEAR(r->targets[0].down->s, 1 * um, tol);
  EXPECT_NEAR(*r->targets[0].B, 4 * um, tol);
  EXPECT_NEAR(*r->targets[0].R, 10 * um, tol);
  EXPECT_NEAR(*r->targets[1].R, 8 * um, tol);
  EXPECT_NEAR(*r->targets[1].mean_bidirectional, 4 * um, tol);
  EXPECT_NEAR(*r->A, 10 * um, tol);
  EXPECT_NEAR(*r->E, 5 * um, tol);
  EXPECT_NEAR(*r->M, 2 * um, tol);
  EXPECT_NEAR(*r->R, 10 * um, tol);
  EXPECT_NEAR(*r->B, 4 * um, tol);
  EXPECT_NEAR(*r->B_mean, 3 * um, tol);
  EXPECT_NEAR(r->up->A, 8 * um, tol);
  EXPECT_NEAR(r->down->A, 9 * um, tol);
  EXPECT_NEAR(r->up->E, 1 * um, tol);
  EXPECT_NEAR(r->down->E, 3 * um, tol);
  EXPECT_NEAR(r->up->R, 8 * um, tol);
  EXPECT_NEAR(r->down->R, 8 * um, tol);
  // y never moves: no approach, no readings.
  EXPECT_FALSE(evaluate_positioning(rec, "y", o));
}

// The standard's formulas written out again, independently of the library.
struct Expected {
  double A, E, M, R, B;
};
Expected independent(const Table& dev) {
  std::vector<double> mean[2], s[2], xbar, b, r;
  for (const auto& target : dev) {
    for (int d = 0; d < 2; ++d) {
      const auto& v = target[d];
      double m = 0;
      for (double x : v)
        m += x;
      m /= double(v.size());
      double q = 0;
      for (double x : v)
        q += (x - m) * (x - m);
      mean[d].push_back(m);
      s[d].push_back(std::sqrt(q / double(v.size() - 1)));
    }
    const std::size_t i = mean[0].size() - 1;
    xbar.push_back((mean[0][i] + mean[1][i]) / 2);
    b.push_back(mean[0][i] - mean[1][i]);
    r.push_back(std::max({2 * s[0][i] + 2 * s[1][i] + std::abs(b[i]), 4 * s[0][i], 4 * s[1][i]}));
  }
  double hi = -1e9, lo = 1e9, ehi = -1e9, elo = 1e9;
  for (int d = 0; d < 2; ++d)
    for (std::size_t i = 0; i < dev.size(); ++i) {
      hi = std::max(hi, mean[d][i] + 2 * s[d][i]);
      lo = std::min(lo, mean[d][i] - 2 * s[d][i]);
      ehi = std::max(ehi, mean[d][i]);
      elo = std::min(elo, mean[d][i]);
    }
  Expected e;
  e.A = hi - lo;
  e.E = ehi - elo;
  e.M = *std::max_element(xbar.begin(), xbar.end()) - *std::min_element(xbar.begin(), xbar.end());
  e.R = *std::max_element(r.begin(), r.end());
  e.B = 0;
  for (double x : b)
    e.B = std::max(e.B, std::abs(x));
  return e;
}

TEST(Iso230Positioning, SeededFiveTargetsFiveRunsBothDirections) {
  std::mt19937 rng(230);
  std::normal_distribution<double> noise(0.0, 0.0015);
  const std::vector<double> targets{0, 97.5, 203.1, 301.7, 398.2};
  Table dev(targets.size());
  for (std::size_t i = 0; i < targets.size(); ++i)
    for (int d = 0; d < 2; ++d)
      for (int run = 0; run < 5; ++run)
        dev[i][d].push_back(2e-5 * targets[i] + (d == 0 ? 0.004 : -0.004) + noise(rng));
  // Overrun points dwell long enough to be read, but only ever from one side.
  auto file = write_cycle("seeded.csv", targets, dev, 1.0, false);
  auto rec = read_recording(file);
  auto r = evaluate_positioning(rec, "x", {});
  ASSERT_TRUE(r);
  EXPECT_EQ(r->measured_channel, "x_act");
  ASSERT_EQ(r->targets.size(), 5u);
  for (std::size_t i = 0; i < targets.size(); ++i) {
    EXPECT_NEAR(r->targets[i].target, targets[i], 1e-9);
    ASSERT_EQ(r->targets[i].up->runs(), 5);
    ASSERT_EQ(r->targets[i].down->runs(), 5);
    EXPECT_NEAR(r->targets[i].down->deviations[3], dev[i][1][3], 1e-9);
  }
  const auto e = independent(dev);
  EXPECT_NEAR(*r->A, e.A, 1e-9);
  EXPECT_NEAR(*r->E, e.E, 1e-9);
  EXPECT_NEAR(*r->M, e.M, 1e-9);
  EXPECT_NEAR(*r->R, e.R, 1e-9);
  EXPECT_NEAR(*r->B, e.B, 1e-9);
  EXPECT_NEAR(*r->B, 0.008, 0.004);  // the planted reversal, roughly
  // The two overrun positions were read but not evaluated.
  bool noted = false;
  for (const auto& n : r->notes)
    noted = noted || n.find("2 standstill position(s)") != std::string::npos;
  EXPECT_TRUE(noted);
}

TEST(Iso230Positioning, UnidirectionalWhenOnlyOneSideHasEnoughRuns) {
  std::vector<PositionReading> readings;
  for (int run = 0; run < 3; ++run)
    for (double target : {0.0, 50.0, 100.0})
      readings.push_back({0, 1, target, target + 0.001 * run, +1});
  readings.push_back({0, 1, 50.0, 50.0, -1});  // one downward reading is not enough
  auto r = evaluate_positioning("x", readings, {});
  ASSERT_TRUE(r);
  EXPECT_FALSE(r->A);
  ASSERT_TRUE(r->up);
  EXPECT_FALSE(r->down);
  EXPECT_NEAR(r->up->E, 0.0, 1e-12);        // every target has mean 0.001
  EXPECT_NEAR(r->up->R, 4 * 0.001, 1e-12);  // s = 0.001 for {0, 0.001, 0.002}
}

TEST(Iso230Positioning, ReadingsFindApproachDirectionAfterOverrun) {
  // Up to 10 (dwell), overrun to 12 without dwelling, back to 10 (dwell):
  // the second reading is approached downwards although both are at 10.
  std::vector<double> t, cmd;
  double now = 0;
  auto add = [&](double c, int n) {
    for (int k = 0; k < n; ++k)
      t.push_back(now), cmd.push_back(c), now += 0.1;
  };
  for (int k = 0; k <= 10; ++k)
    add(k, 1);
  add(10, 10);
  add(11, 1);
  add(12, 1);
  add(11, 1);
  add(10, 10);
  auto readings = find_position_readings(t, cmd, cmd, {});
  ASSERT_EQ(readings.size(), 2u);
  EXPECT_EQ(readings[0].direction, +1);
  EXPECT_EQ(readings[1].direction, -1);
  EXPECT_NEAR(readings[1].target, 10, 1e-12);
}

}  // namespace
}  // namespace truecut::analysis
