// The named stages of the diagnosis pipelines on small synthetic inputs,
// each against an expectation computed here independently.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "diagnose_steps.hpp"
#include "fit_steps.hpp"
#include "surface_steps.hpp"

namespace truecut::analysis::diagnosis {
namespace {

std::vector<double> white_noise(std::size_t n, double sigma, unsigned seed) {
  std::mt19937 gen(seed);
  std::normal_distribution<double> g(0.0, sigma);
  std::vector<double> v(n);
  for (double& x : v)
    x = g(gen);
  return v;
}

double sample_std(const std::vector<double>& v) {
  double m = 0;
  for (double x : v)
    m += x;
  m /= double(v.size());
  double ss = 0;
  for (double x : v)
    ss += (x - m) * (x - m);
  return std::sqrt(ss / double(v.size() - 1));
}

// One joint (x) sampled every millisecond, commanded along a ramp.
Trace one_axis_trace(std::size_t n) {
  Trace tr;
  tr.axes = {sim::kX};
  tr.meas[sim::kX] = true;
  for (std::size_t k = 0; k < n; ++k) {
    tr.t_s.push_back(1e-3 * double(k));
    tr.cmd[sim::kX].push_back(0.01 * double(k));
  }
  return tr;
}

TEST(DiagnosisStages, NoiseFloorOfWhiteNoiseUnderASmoothModelError) {
  const std::size_t n = 4000;
  const double sigma = 0.002;
  Trace tr = one_axis_trace(n);
  const auto noise = white_noise(n, sigma, 7);
  // A slow model error far above the noise: the floor must not see it.
  tr.target[sim::kX].resize(n);
  for (std::size_t k = 0; k < n; ++k)
    tr.target[sim::kX][k] = 0.5 * std::sin(2 * std::numbers::pi * tr.t_s[k] / 4.0) + noise[k];
  Simulated sim0;
  sim0.target[sim::kX].assign(n, 0.0);
  const std::vector<char> train(n, 1);
  const NoiseFloors f =
      estimate_noise_floors(tr, sim0, train, sim::MachineParams{}, InterpolationError{});
  ASSERT_EQ(f.axes.size(), 1u);
  EXPECT_EQ(f.axes[0].axis, "x");
  EXPECT_EQ(f.axes[0].target, "x_meas");
  EXPECT_EQ(f.axes[0].resolution_mm, 0.0);  // continuous data: no grid
  const double expected = sample_std(noise);
  EXPECT_NEAR(f.axes[0].noise_floor_mm, expected, 0.1 * expected);
  EXPECT_NEAR(f.noise_only[sim::kX], f.axes[0].noise_floor_mm, 1e-15);  // no interpolation error
  ASSERT_EQ(f.w.size(), 1u);
  EXPECT_DOUBLE_EQ(f.w[0], 1.0 / f.axes[0].noise_floor_mm);
  EXPECT_TRUE(f.sw.empty());
}

TEST(DiagnosisStages, NoiseFloorIsNeverBelowTheResolution) {
  const std::size_t n = 500;
  const double q = 0.001;  // a 1 µm grid, the target moving one count at a time
  Trace tr = one_axis_trace(n);
  tr.target[sim::kX].resize(n);
  for (std::size_t k = 0; k < n; ++k)
    tr.target[sim::kX][k] = q * std::round(std::sin(double(k) / 7.0) * 3.0 + double(k % 5));
  Simulated sim0;
  sim0.target[sim::kX] = tr.target[sim::kX];  // the model matches to the count
  const NoiseFloors f = estimate_noise_floors(tr, sim0, std::vector<char>(n, 1),
                                              sim::MachineParams{}, InterpolationError{});
  ASSERT_EQ(f.axes.size(), 1u);
  EXPECT_NEAR(f.axes[0].resolution_mm, q, 1e-12);
  EXPECT_NEAR(f.axes[0].noise_floor_mm, q / std::sqrt(12.0), 1e-12);
}

TEST(DiagnosisStages, MasksLeaveOutAPlantedSpikeTheMarginsAndSplitTheEnd) {
  const std::size_t n = 1000;
  Trace tr = one_axis_trace(n);
  tr.target[sim::kX] = tr.cmd[sim::kX];
  const std::size_t spike = 500;
  tr.cmd[sim::kX][spike] += 5.0;  // one sample out and straight back
  const double margin = 0.02, fraction = 0.25;
  const Masks m = make_masks(tr, margin, fraction);
  EXPECT_EQ(m.excluded, 3u);
  std::size_t train = 0, held = 0;
  const double split = tr.t_s.back() - fraction * tr.t_s.back();
  for (std::size_t k = 0; k < n; ++k) {
    const double t = tr.t_s[k];
    const bool glitch = k + 1 >= spike && k <= spike + 1;
    const bool valid = t >= margin && t <= tr.t_s.back() - margin && !glitch;
    EXPECT_EQ(bool(m.valid[k]), valid) << k;
    EXPECT_EQ(bool(m.heldout[k]), valid && t >= split) << k;
    EXPECT_EQ(bool(m.train[k]), valid && t < split) << k;
    train += m.train[k], held += m.heldout[k];
  }
  EXPECT_GT(train, 600u);
  EXPECT_GT(held, 200u);
}

TEST(DiagnosisStages, BestDelayFindsAPlantedDelay) {
  const std::size_t n = 2000;
  Trace tr = one_axis_trace(n);
  const double planted = 0.0123;  // s: the recorder logs this late
  Simulated sim;
  sim.target[sim::kX].resize(n);
  tr.target[sim::kX].resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double t = tr.t_s[k];
    sim.target[sim::kX][k] = 10 * std::sin(2 * std::numbers::pi * t);
    tr.target[sim::kX][k] = 10 * std::sin(2 * std::numbers::pi * (t - planted)) + 0.3;
  }
  // The first samples read the simulation before its start (held there).
  std::vector<char> use(n, 1);
  std::fill(use.begin(), use.begin() + 50, 0);
  const double d = best_delay(tr, sim, use, {1.0}, {}, -0.05, 0.05, 2.5e-4);
  EXPECT_NEAR(d, planted, 1e-5);
  // The offset is profiled out: at the planted delay the residual is the
  // interpolation error of a 1 Hz sine sampled at 1 kHz, far below its own size.
  EXPECT_LT(delay_rss(tr, sim, use, {1.0}, {}, d), 1e-6 * delay_rss(tr, sim, use, {1.0}, {}, 0));
}

// A candidate of one column whose coefficient is always physical.
Candidate column_candidate(const std::string& group, const Eigen::VectorXd& column) {
  Candidate c;
  c.effect = group;
  c.group = group;
  c.X = column;
  c.apply = [](sim::MachineParams&, const Eigen::VectorXd&) { return true; };
  return c;
}

TEST(DiagnosisStages, ForwardSelectionByBicChoosesThePlantedEffect) {
  const Eigen::Index n = 600;
  const auto noise = white_noise(std::size_t(n), 1.0, 11);  // weighted units: the floor is 1
  Eigen::VectorXd a(n), b(n), c(n), r(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const double s = double(k) / double(n);
    a[k] = std::sin(2 * std::numbers::pi * 3 * s);
    b[k] = s * s - 1.0 / 3;
    c[k] = std::cos(2 * std::numbers::pi * 17 * s);
    r[k] = 2.0 * a[k] + noise[std::size_t(k)];
  }
  const std::vector<Candidate> cands = {column_candidate("a", a), column_candidate("b", b),
                                        column_candidate("c", c)};
  Layout layout;
  layout.axes = {sim::kX};
  layout.weight = {1.0};
  layout.index.resize(1);
  for (Eigen::Index k = 0; k < n; ++k)
    layout.index[0].push_back(std::size_t(k));
  double n_eff = 0;
  const Selection sel = forward_select(cands, r, 10.0, 0.1, layout, sim::MachineParams{}, n_eff);
  ASSERT_EQ(sel.chosen.size(), 1u);
  EXPECT_EQ(sel.chosen[0]->group, "a");
  // The coefficient is the least-squares one: (a·r)/(a·a).
  ASSERT_EQ(sel.coef.size(), 1);
  EXPECT_NEAR(sel.coef[0], a.dot(r) / a.dot(a), 1e-9);
  EXPECT_NEAR(sel.coef[0], 2.0, 0.2);
  // ΔBIC against the empty model, with the white noise's n_eff ≈ n.
  EXPECT_GT(n_eff, 0.8 * double(n));
  const double rss0 = r.squaredNorm(), rss1 = (r - sel.coef[0] * a).squaredNorm();
  EXPECT_NEAR(sel.delta_bic[0], n_eff * std::log(rss1 / rss0) + std::log(n_eff), 1e-6);
  EXPECT_LT(sel.delta_bic[0], -10.0);
}

TEST(DiagnosisStages, ForwardSelectionKeepsNothingFromNoiseAlone) {
  const Eigen::Index n = 600;
  const auto noise = white_noise(std::size_t(n), 1.0, 3);
  Eigen::VectorXd a(n), r(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    a[k] = std::sin(2 * std::numbers::pi * 3 * double(k) / double(n));
    r[k] = noise[std::size_t(k)];
  }
  Layout layout;
  layout.axes = {sim::kX};
  layout.weight = {1.0};
  layout.index.resize(1);
  for (Eigen::Index k = 0; k < n; ++k)
    layout.index[0].push_back(std::size_t(k));
  double n_eff = 0;
  const Selection sel =
      forward_select({column_candidate("a", a)}, r, 10.0, 0.1, layout, sim::MachineParams{}, n_eff);
  EXPECT_TRUE(sel.chosen.empty());
}

TEST(DiagnosisStages, SurfaceNoiseFloorPairsNeighboursOnTheSameSurfaceOnly) {
  // Two interleaved surfaces 0.1 mm apart, the second offset by 1 mm: a
  // floor from neighbours across surfaces would see the offset.
  const std::size_t per_surface = 1500;
  const double sigma = 0.003;
  const auto noise = white_noise(2 * per_surface, sigma, 5);
  std::vector<sim::measure::CmmPoint> points;
  Eigen::VectorXd r(Eigen::Index(2 * per_surface));
  std::vector<std::size_t> train;
  for (std::size_t i = 0; i < 2 * per_surface; ++i) {
    sim::measure::CmmPoint p;
    p.surface = int(i % 2);
    p.position_mm = {double(i / 2), 0.1 * double(i % 2), 0.0};
    points.push_back(p);
    r[Eigen::Index(i)] = noise[i] + (i % 2 ? 1.0 : 0.0);
    train.push_back(i);
  }
  const SurfaceNoise s = surface_noise_floor(points, r, train);
  const double expected = sample_std(noise);
  EXPECT_NEAR(s.floor_mm, expected, 0.1 * expected);
  // No point with a neighbour on its surface: the RMS of the residual.
  for (std::size_t i = 0; i < points.size(); ++i)
    points[i].surface = int(i);
  const SurfaceNoise alone = surface_noise_floor(points, r, train);
  EXPECT_NEAR(alone.floor_mm, r.norm() / std::sqrt(double(r.size())), 1e-15);
  EXPECT_EQ(alone.sxx, 0.0);
}

}  // namespace
}  // namespace truecut::analysis::diagnosis
