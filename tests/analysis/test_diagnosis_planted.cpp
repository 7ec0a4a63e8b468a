// The diagnosis on recordings from the independent generator
// (planted_recording.hpp: its own physics and paths, not sim::MachineModel),
// diagnosed against the ideal machine as `truecut diagnose` does without
// --machine: each effect alone, effects concealed under others, a small
// effect next to a large one, and negative controls (servo lag and noise
// only). Judged by planted_cases.hpp: every planted parameter within ±15 %
// (or ±1 µm, ±1 µrad, ±1 µm/m), nothing reported that was not planted.
// One seed per case here; the sweep over 20 seeds and three magnitudes
// per effect is analysis_planted_sweep (docs/diagnosis.md).
#include <gtest/gtest.h>

#include "planted_cases.hpp"
#include "test_paths.hpp"

namespace truecut::test::planted {
namespace {

void expect_right(const Case& c) {
  const auto r = diagnose_case(c, scratch_dir());
  const Verdict v = judge(c, r);
  EXPECT_TRUE(v.pass) << c.name << ": " << v.why << "\n"
                      << analysis::diagnosis::diagnosis_summary(r);
}

// The sweep's paths (two ISO 230-2 cycles, 1.5 turns each way: the
// held-out last 30 % must still cover the travel); one seed per case here,
// the sweep runs 20.
Case base(const std::string& name, PathKind path, unsigned seed) {
  Case c;
  c.name = name;
  c.spec.path = path;
  c.spec.seed = seed;
  c.spec.noise_mm = 0.001;
  if (path == PathKind::kContour3) c.spec.record = {true, true, true};
  return c;
}

// Negative control: servo lag and noise only, on the ISO 230-2 stepping.
TEST(DiagnosisPlanted, ServoLagAndNoiseOnlyOnIsoSteps) {
  Case c = base("negative_iso", PathKind::kIso230X, 3);
  c.plant.axes[0] = servo(40, 0.9);
  expect_servo(c, "x", 40, 0.9);
  expect_right(c);
}

// Negative control on circles: the loop's (Kv, ff1) is found (not a pure
// lag of Kv 400 with pitch and squareness terms standing in for the rest).
TEST(DiagnosisPlanted, ServoLagAndNoiseOnlyOnCircles) {
  Case c = base("negative_circle", PathKind::kCircleXY, 1);
  c.plant.axes[0] = servo(40, 0.9);
  c.plant.axes[1] = servo(35, 0.85);
  expect_servo(c, "x", 40, 0.9);
  expect_servo(c, "y", 35, 0.85);
  expect_right(c);
}

// A loop with nearly full feed-forward (Kv 100 / ff1 0.97, Y at Kv 80) on
// circles, the sweep's seed 4: its split is refined in round 1 beside pitch
// scales and a drift standing in for the lag, which the elimination drops
// afterwards; refined only there it stayed at Kv 120 for 100 and 109 for
// 80. The split is refined again on the model that stays.
TEST(DiagnosisPlanted, ServoLagNearFullFeedForwardOnCircles) {
  expect_right(sweep_case(Effect::kServoLag, 2, 4));
}

// Backlash under noise and servo lag on a back-and-forth (ISO 230-2) path
// that starts from a standstill with the gap closed (no thermal drift
// standing in for the gap's unknown start).
TEST(DiagnosisPlanted, BacklashUnderServoLagOnIsoSteps) {
  Case c = base("backlash_iso", PathKind::kIso230X, 1);
  c.plant.axes[0] = servo(40, 0.9);
  c.plant.axes[0].backlash_mm = 0.006;
  expect_servo(c, "x", 40, 0.9);
  c.expected.push_back({"backlash", "x", "play_mm", 0.006, 0.001});
  expect_right(c);
}

// Friction 100 N under servo lag on the contour, the sweep's seed 8: a
// pitch scale of Z (-45 µm/m, not planted) and Z's split (Kv 77 / ff1 0.81
// for 40 / 0.9) pulled each other; priced without the pitch at the split it
// pulled, the pitch stayed. It goes when the splits refined without it fit
// as well.
TEST(DiagnosisPlanted, PitchStandingInForAServoSplitIsDropped) {
  expect_right(sweep_case(Effect::kReversalSpike, 1, 8));
}

// Friction 30 N under servo lag on the contour, the sweep's seed 12: once
// reported with Z's split at Kv 122.9 / ff1 0.693 (for 40 / 0.9) beside a
// pitch scale of Z (-52 µm/m) that was not planted. Every loop within
// ±15 % and nothing reported that was not planted.
TEST(DiagnosisPlanted, FrictionSeed12KeepsZsSplitWithoutAPitch) {
  expect_right(sweep_case(Effect::kReversalSpike, 0, 12));
}

// A reversal spike (Coulomb friction) under servo lag, on the 3-axis
// contour: the loop found by the diagnosis must not bend to mimic the
// spikes (Kv 79 / ff1 0.8 with 169 N for 100 N planted; at 300 N a pure lag
// of Kv 420 and no friction at all).
TEST(DiagnosisPlanted, ReversalSpikeUnderServoLag) {
  Case c = base("spike", PathKind::kContour3, 2);
  for (int j = 0; j < 3; ++j)
    c.plant.axes[j] = servo(40, 0.9);
  c.plant.axes[0].coulomb_n = 300;
  for (const char* a : {"x", "y", "z"})
    expect_servo(c, a, 40, 0.9);
  c.expected.push_back({"reversal_spike", "x", "coulomb_n", 300, 0.0});
  expect_right(c);
}

// Thermal drift on an axis that is not commanded.
TEST(DiagnosisPlanted, ThermalDriftOnAnIdleAxis) {
  Case c = base("thermal_idle", PathKind::kIso230X, 2);
  c.plant.axes[0] = servo(40, 0.9);
  c.plant.axes[1].thermal_gain_mm = 0.008;
  c.plant.axes[1].thermal_tau_s = 3;
  expect_servo(c, "x", 40, 0.9);
  c.expected.push_back({"thermal_drift", "y", "gain_mm", 0.008, 0.001});
  c.expected.push_back({"thermal_drift", "y", "tau_s", 3, 0.0});
  expect_right(c);
}

// Thermal drift under a pitch error and servo lag, on the moving axis.
TEST(DiagnosisPlanted, ThermalDriftUnderPitchAndServoLag) {
  Case c = base("thermal_pitch", PathKind::kIso230X, 1);
  c.plant.axes[0] = servo(40, 0.9);
  c.plant.axes[0].pitch_scale_um_per_m = 60;
  c.plant.axes[0].pitch_reference_mm = 20;
  c.plant.axes[0].thermal_gain_mm = 0.008;
  c.plant.axes[0].thermal_tau_s = 3;
  expect_servo(c, "x", 40, 0.9);
  c.expected.push_back({"pitch_error", "x", "scale_um_per_m", 60, 1.0});
  c.expected.push_back({"thermal_drift", "x", "gain_mm", 0.008, 0.001});
  c.expected.push_back({"thermal_drift", "x", "tau_s", 3, 0.0});
  expect_right(c);
}

// A small effect next to a large one: a
// 25 µrad squareness (0.25 µm on the circle's radius) next to a 15 µm
// backlash, on circles.
TEST(DiagnosisPlanted, SmallSquarenessNextToLargeBacklash) {
  Case c = base("square_backlash", PathKind::kCircleXY, 1);
  c.plant.axes[0] = servo(40, 0.9);
  c.plant.axes[1] = servo(35, 0.85);
  c.plant.axes[0].backlash_mm = 0.015;
  c.plant.xy_urad = 25;
  expect_servo(c, "x", 40, 0.9);
  expect_servo(c, "y", 35, 0.85);
  c.expected.push_back({"backlash", "x", "play_mm", 0.015, 0.001});
  c.expected.push_back({"squareness", "xy", "xy_urad", 25, 1.0});
  expect_right(c);
}

// Pitch error alone (no servo) on the stepping, squareness alone on circles.
TEST(DiagnosisPlanted, PitchErrorAlone) {
  Case c = base("pitch", PathKind::kIso230X, 4);
  c.plant.axes[0].pitch_scale_um_per_m = 50;
  c.plant.axes[0].pitch_reference_mm = 20;
  c.expected.push_back({"pitch_error", "x", "scale_um_per_m", 50, 1.0});
  expect_right(c);
}

TEST(DiagnosisPlanted, SquarenessAlone) {
  Case c = base("square", PathKind::kCircleXY, 5);
  c.plant.xy_urad = 60;
  c.expected.push_back({"squareness", "xy", "xy_urad", 60, 1.0});
  expect_right(c);
}

}  // namespace
}  // namespace truecut::test::planted
