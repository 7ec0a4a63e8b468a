// The named stages of the diagnosis pipelines on small synthetic inputs,
// each against an expectation computed here independently.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "diagnose_steps.hpp"
#include "fit_steps.hpp"
#include "surface_steps.hpp"
#include "test_paths.hpp"
#include "trace.hpp"
#include "truecut/analysis/recording.hpp"
#include "truecut/sim/machine_model.hpp"

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

// A recording written here from its own kinematics (not MachineModel),
// sampled every 100 ms with ±1 ms jitter: a 20 mm/s back-and-forth with
// sharp reversals, a dwell with a 5 mm step of the command, a 300 mm/s fast
// move out and back and a slow back-and-forth, every speed change ramped at
// 2000 mm/s²; the actual position a first-order lag (10 ms) of the command
// with 2 µm noise, recorded in 1 µm steps.
struct Planted {
  std::vector<double> t, cmd, act;
};
Planted planted_recording() {
  Planted p;
  std::mt19937 gen(7);
  std::normal_distribution<double> noise(0.0, 0.002);
  std::uniform_real_distribution<double> jitter(-0.001, 0.001);
  const double h = 1e-3, tau = 0.01;
  double x = 0, v = 0, act = 0, next = 0;
  for (int i = 0; i < 60000; ++i) {
    const double t = i * h;
    double want = 0;
    if (t < 20)
      want = std::fmod(t, 4.0) < 2.0 ? 20.0 : -20.0;
    else if (t >= 25 && t < 27)
      want = 300.0;
    else if (t >= 27 && t < 29)
      want = -300.0;
    else if (t >= 35)
      want = std::fmod(t, 3.0) < 1.5 ? 5.0 : -5.0;
    v += std::clamp(want - v, -2000 * h, 2000 * h);
    x += v * h;
    const double c = x + (t >= 22.0 && t < 24.0 ? 5.0 : 0.0);
    act += (c - act) * h / tau;
    if (t >= next) {
      p.t.push_back(t);
      p.cmd.push_back(c);
      p.act.push_back(std::round((act + noise(gen)) * 1000.0) / 1000.0);
      next = 0.1 * double(p.t.size()) + jitter(gen);
    }
  }
  return p;
}

std::vector<std::size_t> rows_of(const std::vector<Glitch>& g) {
  std::vector<std::size_t> r;
  for (const auto& x : g)
    r.push_back(x.row);
  return r;
}

TEST(DiagnosisStages, GlitchRowsArePlantedSpikesNotReversalsStepsOrFastMoves) {
  Planted p = planted_recording();
  ASSERT_GT(p.t.size(), 590u);
  // The clean recording has none: reversals, the dwell, the command step
  // and the fast move are motion.
  EXPECT_TRUE(isolated_glitches(p.t, p.cmd).empty()) << rows_of(isolated_glitches(p.t, p.cmd))[0];
  EXPECT_TRUE(isolated_glitches(p.t, p.act).empty()) << rows_of(isolated_glitches(p.t, p.act))[0];
  // Planted: a jump to a home position during the 20 mm/s move (command and
  // actual), 0.5 mm on the command in the dwell, 3 mm on the actual
  // position only after the step, and one two rows wide (not isolated).
  const std::size_t home = 55, small = 210, still = 245, wide = 500;
  p.cmd[home] = p.act[home] = 198.0;
  p.cmd[small] -= 0.5;
  p.act[still] += 3.0;
  p.act[wide] += 40, p.act[wide + 1] += 40;
  const auto gc = isolated_glitches(p.t, p.cmd), ga = isolated_glitches(p.t, p.act);
  EXPECT_EQ(rows_of(gc), (std::vector<std::size_t>{home, small}));
  EXPECT_EQ(rows_of(ga), (std::vector<std::size_t>{home, still}));
  if (gc.size() == 2) {
    EXPECT_NEAR(gc[1].deviation, 0.5, 1e-9);
  }
  if (ga.size() == 2) {
    EXPECT_NEAR(ga[1].deviation, 3.0, 0.02);
  }
}

TEST(DiagnosisStages, MasksLeaveOutGlitchRowsListThemAndTheCommandIsRepaired) {
  Planted p = planted_recording();
  const std::size_t on_cmd = 210, on_act = 245;
  const double clean = p.cmd[on_cmd];
  p.cmd[on_cmd] += 50.0;
  p.act[on_act] -= 2.0;
  Trace tr;
  tr.axes = {sim::kZ};
  tr.t_s = p.t;
  tr.cmd[sim::kZ] = p.cmd;
  tr.target[sim::kZ] = p.act;
  const Masks m = make_masks(tr, 0.5, 0.0);
  ASSERT_EQ(m.glitch_rows.size(), 2u);
  EXPECT_EQ(m.glitch_rows[0].row, on_cmd);
  EXPECT_EQ(m.glitch_rows[0].column, "z_cmd");
  EXPECT_NEAR(m.glitch_rows[0].deviation_mm, 50.0, 1e-6);
  EXPECT_EQ(m.glitch_rows[1].row, on_act);
  EXPECT_EQ(m.glitch_rows[1].column, "z_act");
  EXPECT_FALSE(m.valid[on_cmd]);
  EXPECT_FALSE(m.valid[on_act]);
  EXPECT_TRUE(m.valid[on_cmd - 3]);
  EXPECT_GE(m.excluded, 2u);
  repair_command_glitches(tr, m.glitch_rows);
  EXPECT_NEAR(tr.cmd[sim::kZ][on_cmd], clean, 1e-9);     // in the dwell: the line is the dwell
  EXPECT_EQ(tr.target[sim::kZ][on_act], p.act[on_act]);  // targets are only left out
}

// The real UMich recordings (data/umich_cnc_mill): the rows the rule finds,
// per experiment, column by column (0 = the first data row). Experiment 1
// has none; the spliced blocks of the other experiments (ten rows or more
// at another place) are not isolated rows.
TEST(DiagnosisStages, GlitchRowsOfTheUmichExperiments) {
  const std::string cols[6][2] = {{"x_cmd", "X1_CommandPosition"}, {"x_act", "X1_ActualPosition"},
                                  {"y_cmd", "Y1_CommandPosition"}, {"y_act", "Y1_ActualPosition"},
                                  {"z_cmd", "Z1_CommandPosition"}, {"z_act", "Z1_ActualPosition"}};
  std::string spec = "t=@index*0.1";
  for (const auto& c : cols)
    spec += "," + c[0] + "=" + c[1];
  RecordingOptions o;
  o.map = parse_column_map(spec);
  using Found = std::set<std::pair<std::size_t, std::string>>;
  std::map<int, Found> expected = {
      {2,
       {{313, "x_cmd"},
        {313, "x_act"},
        {313, "y_cmd"},
        {313, "y_act"},
        {313, "z_cmd"},
        {313, "z_act"},
        {525, "x_cmd"},
        {525, "x_act"},
        {525, "y_cmd"},
        {525, "y_act"},
        {525, "z_cmd"},
        {525, "z_act"},
        {956, "x_act"},
        {1528, "x_cmd"},
        {1528, "x_act"},
        {1528, "y_cmd"},
        {1528, "y_act"},
        {1528, "z_cmd"},
        {1528, "z_act"}}},
      {14, {{231, "y_cmd"}, {231, "y_act"}}},
      {15, {{466, "z_cmd"}, {466, "z_act"}, {1036, "z_cmd"}, {1036, "z_act"}}}};
  for (int e = 1; e <= 18; ++e) {
    char name[32];
    std::snprintf(name, sizeof name, "experiment_%02d.csv", e);
    const auto file = truecut::test::data_dir() / "umich_cnc_mill" / name;
    ASSERT_TRUE(std::filesystem::is_regular_file(file)) << file;
    const Recording rec = read_recording(file, o);
    Found found;
    for (const auto& c : cols)
      for (const Glitch& g : isolated_glitches(rec.t_s, rec.channel(c[0])))
        found.insert({g.row, c[0]});
    EXPECT_EQ(found, expected[e]) << "experiment " << e;
  }
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

// The re-simulation as it was before it went joint by joint: every joint
// through sim::MachineModel::step at once.
Simulated resimulate_by_step(const sim::MachineParams& params, const Trace& tr,
                             double max_period_s) {
  const sim::MachineModel model(params);
  sim::MachineState state;
  sim::MachineInputs in;
  sim::MachineOutputs out;
  Simulated sim;
  const std::size_t n = tr.rows();
  for (int j : tr.axes) {
    sim.target[j].resize(n);
    sim.motor[j].resize(n);
  }
  for (int j = 0; j < sim::kJointCount; ++j)
    if (sim.motor[j].empty() && !tr.cmd[j].empty()) sim.motor[j].resize(n);
  auto cmd_at = [&](int j, std::size_t k, std::size_t k1, double s, double dt) {
    if (tr.cmd[j].empty()) return 0.0;
    const double p0 = tr.cmd[j][k], p1 = tr.cmd[j][k1];
    if (s == 0.0 || k1 == k) return p0;
    if (tr.cmd_slope[j].empty()) return p0 + (p1 - p0) * s;
    const double s2 = s * s, s3 = s2 * s;
    return (2 * s3 - 3 * s2 + 1) * p0 + (s3 - 2 * s2 + s) * dt * tr.cmd_slope[j][k] +
           (3 * s2 - 2 * s3) * p1 + (s3 - s2) * dt * tr.cmd_slope[j][k1];
  };
  const double nominal_dt = median_period(tr.t_s);
  for (std::size_t k = 0; k < n; ++k) {
    double dt = k + 1 < n ? tr.t_s[k + 1] - tr.t_s[k] : tr.t_s[k] - tr.t_s[k - 1];
    if (std::abs(dt - nominal_dt) <= 1e-6 * nominal_dt) dt = nominal_dt;
    const int sub = substeps_for(dt, max_period_s);
    const std::size_t k1 = std::min(k + 1, n - 1);
    for (int i = 0; i < sub; ++i) {
      for (int j = 0; j < sim::kJointCount; ++j)
        in.pos_cmd[j] = cmd_at(j, k, k1, double(i) / sub, dt);
      in.spindle_power_kw = tr.spindle_power_kw.empty() ? 0.0 : tr.spindle_power_kw[k];
      model.step(state, in, dt / sub, out);
      if (i != 0) continue;
      for (int j = 0; j < sim::kJointCount; ++j) {
        if (!sim.motor[j].empty()) sim.motor[j][k] = out.pos_act[j];
        if (sim.target[j].empty()) continue;
        sim.target[j][k] =
            !tr.meas[j] ? out.pos_act[j] : (j < 3 ? out.xyz_true[j] : out.pos_true[j]);
      }
    }
  }
  return sim;
}

void expect_same_bits(const Simulated& a, const Simulated& b) {
  for (int j = 0; j < sim::kJointCount; ++j) {
    ASSERT_EQ(a.target[j].size(), b.target[j].size()) << j;
    ASSERT_EQ(a.motor[j].size(), b.motor[j].size()) << j;
    for (std::size_t k = 0; k < a.target[j].size(); ++k)
      ASSERT_EQ(a.target[j][k], b.target[j][k]) << "target of joint " << j << " at " << k;
    for (std::size_t k = 0; k < a.motor[j].size(); ++k)
      ASSERT_EQ(a.motor[j][k], b.motor[j][k]) << "motor of joint " << j << " at " << k;
  }
}

// The re-simulation runs joint by joint (and reads back the joints a cache
// has seen with the same parameters): the same numbers, bit for bit, as
// the whole machine stepped at once, with every joint effect, geometric
// errors coupling the recorded slides, an idle slide drifting, a rotary
// joint and two servo periods per recorded interval.
TEST(DiagnosisStages, ResimulationJointByJointIsTheMachineStepBitForBit) {
  const std::size_t n = 3000;
  Trace tr;
  for (std::size_t k = 0; k < n; ++k) {
    const double t = 2e-3 * double(k);
    tr.t_s.push_back(t);
    tr.cmd[sim::kX].push_back(20 * std::cos(2.0 * t));
    tr.cmd[sim::kZ].push_back(5 * std::sin(1.3 * t) + 0.3 * std::floor(t));
    tr.cmd[sim::kA].push_back(30 * std::sin(0.7 * t));
    tr.spindle_power_kw.push_back(t < 3 ? 4.0 : 1.0);
  }
  for (int j : {sim::kX, sim::kZ, sim::kA})
    tr.cmd_slope[j] = command_slopes(tr.t_s, tr.cmd[j]);
  // y idle and recorded, x and y on a measuring system, z on the encoder.
  for (int j : {sim::kX, sim::kY, sim::kZ, sim::kA})
    tr.target[j] = std::vector<double>(n, 0.0);
  tr.cmd[sim::kY] = std::vector<double>(n, 0.0);
  tr.axes = {sim::kX, sim::kY, sim::kZ, sim::kA};
  tr.meas[sim::kX] = tr.meas[sim::kY] = tr.meas[sim::kA] = true;

  sim::MachineParams p;
  for (int j = 0; j < sim::kJointCount; ++j) {
    p.joints[j].present = true;
    p.joints[j].min = -1000, p.joints[j].max = 1000;
    p.joints[j].drive = sim::default_drive(j);
  }
  auto& fx = p.effects;
  fx.servo_lag.enabled = fx.backlash.enabled = fx.reversal_spike.enabled = true;
  fx.pitch_error.enabled = fx.thermal_drift.enabled = true;
  fx.servo_lag.axes[sim::kX] = sim::ServoLagAxis{40, 0.9};
  fx.servo_lag.axes[sim::kZ] = sim::ServoLagAxis{35, 0.5};
  fx.servo_lag.axes[sim::kA] = sim::ServoLagAxis{30, 0.8};
  fx.backlash.axes[sim::kX] = sim::BacklashAxis{0.004};
  fx.reversal_spike.axes[sim::kZ] = sim::ReversalSpikeAxis{150, 0.2};
  fx.pitch_error.axes[sim::kX] = sim::PitchErrorAxis{40, 5, 2, 7, 30};
  fx.thermal_drift.axes[sim::kY] = sim::ThermalDriftAxis{0.01, 2, sim::ThermalDriver::kTime, 10};
  fx.thermal_drift.axes[sim::kZ] =
      sim::ThermalDriftAxis{0.005, 1, sim::ThermalDriver::kSpindlePower, 5};
  fx.squareness.enabled = true;
  fx.squareness.params = {50, 20, -30};
  fx.straightness.enabled = true;
  fx.straightness.params.components[0] = sim::StraightnessComponent{80, 10, 3};

  expect_same_bits(resimulate(p, tr, 1e-3), resimulate_by_step(p, tr, 1e-3));
  ResimCache cache(2);
  sim::MachineParams q = p;  // another x loop: the other joints read back
  q.effects.servo_lag.axes[sim::kX]->kv_per_s = 45;
  sim::MachineParams r = q;  // no squareness: every joint read back
  r.effects.squareness.enabled = false;
  sim::MachineParams u = p;  // the y drift off
  u.effects.thermal_drift.axes[sim::kY].reset();
  for (const auto* m : {&p, &q, &r, &p, &u, &q, &p})
    expect_same_bits(resimulate(*m, tr, 1e-3, &cache), resimulate_by_step(*m, tr, 1e-3));
  // Half a period more per interval: the cache is for one period only.
  expect_same_bits(resimulate(q, tr, 0.7e-3, &cache), resimulate_by_step(q, tr, 0.7e-3));
  EXPECT_EQ(joint_part(p, sim::kY), joint_part(q, sim::kY));
  EXPECT_FALSE(joint_part(p, sim::kX) == joint_part(q, sim::kX));
}

}  // namespace
}  // namespace truecut::analysis::diagnosis
