// Diagnosis of recordings as other recorders write them: sampled slower than
// the servo (the command only known at the samples), quantised and free of
// noise (a simulator's trace), a rapid move among slow ones, a recorder
// glitch, a straightness whose flat point is not the middle of the travel.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "test_diagnosis_checks.hpp"
#include "test_diagnosis_fixtures.hpp"

namespace truecut::analysis::test {
using namespace truecut::sim;
using namespace truecut::sim::test;
namespace {

namespace dg = diagnosis;

MachineDescription with_backlash(MachineDescription d, double play_mm) {
  d.machine.effects.backlash.enabled = true;
  d.machine.effects.backlash.axes[kX] = BacklashAxis{play_mm};
  return d;
}

// A 100 Hz recorder on a 1 kHz servo: the re-simulation reads the command
// between the samples; backlash near the noise is found, nothing else.
TEST(DiagnosisRecorders, BacklashFoundAt100Hz) {
  RecordingSpec spec;
  spec.noise_mm = 0.0015;
  spec.record_every = 10;
  const auto rec = make_recording(with_backlash(believed_with_servo(), 0.004).machine, spec);
  ASSERT_EQ(rec.rows(), 1200u);
  const auto r = run(believed_with_servo(), rec);
  EXPECT_EQ(r.substeps, 10);
  const auto* e = find(r, "backlash", "x");
  ASSERT_NE(e, nullptr) << dg::diagnosis_summary(r);
  expect_covers(*e, "play_mm", 0.004, r);
  EXPECT_EQ(r.explanations.size(), 1u) << dg::diagnosis_summary(r);
  ASSERT_TRUE(r.has_heldout);
  EXPECT_LT(r.heldout.rms_after_mm, 1.5 * spec.noise_mm) << dg::diagnosis_summary(r);
}

// 10 Hz: whole accelerations fall between two samples. The correct model
// must still select nothing (no loop adjustment taken for the
// interpolation's misfit), and the loops' notes say why.
TEST(DiagnosisRecorders, CorrectModelAt10HzSelectsNothing) {
  RecordingSpec spec;
  spec.noise_mm = 0.001;
  spec.record_every = 100;
  spec.duration_s = 30;
  const auto r = run(believed_with_servo(), make_recording(believed_with_servo().machine, spec));
  EXPECT_TRUE(r.explanations.empty()) << dg::diagnosis_summary(r);
  EXPECT_GT(r.axes[0].interpolation_mm, 0.0);
  bool loop_note = false;
  for (const auto& n : r.notes)
    loop_note = loop_note || n.find("1/Kv") != std::string::npos;
  EXPECT_TRUE(loop_note) << dg::diagnosis_summary(r);
}

// A simulator's trace: encoders quantised to 0.1 µm and no noise at all. The
// correct model leaves rounding flips only: nothing missing (a floor from
// the MAD of those flips alone would be ~0 and find "effects" of 1 nm).
TEST(DiagnosisRecorders, QuantisedNoiseFreeTraceOfTheCorrectModelSelectsNothing) {
  MachineDescription model = believed_with_servo();
  for (int j : {kX, kY})
    model.machine.joints[j].drive.encoder_resolution = 1e-4;
  model.machine.effects.reversal_spike.enabled = true;
  model.machine.effects.reversal_spike.axes[kX] = ReversalSpikeAxis{80.0, 0.0};
  RecordingSpec spec;
  spec.noise_mm = 0.0;
  spec.meas = false;
  spec.duration_s = 8;
  const auto r = run(model, make_recording(model.machine, spec));
  EXPECT_TRUE(r.explanations.empty()) << dg::diagnosis_summary(r);
  EXPECT_NEAR(r.axes[0].resolution_mm, 1e-4, 1e-9) << dg::diagnosis_summary(r);
  EXPECT_GE(r.axes[0].noise_floor_mm, 1e-4 / std::sqrt(12.0));
  EXPECT_EQ(r.verdict, "nothing missing: the residual is at the noise floor")
      << dg::diagnosis_summary(r);
}

// The same without noise on the tracked tool-centre point and the encoders:
// the joints' 0.1 µm steps carried through the kinematics are the TCP's
// floor, and no rotary-axis location is made up from them.
TEST(DiagnosisRecorders, NoiseFreeTcpOfCorrectKinematicsSelectsNothing) {
  MachineDescription d = trunnion_with_servo();
  for (int j = 0; j < kJointCount; ++j)
    d.machine.joints[j].drive.encoder_resolution = 1e-4;
  dg::DiagnosisOptions o;
  const auto rec = five_axis_recording(d.machine, 4, 0.0, 0.0);
  const auto r = dg::diagnose(rec, nullptr, d, o);
  EXPECT_TRUE(r.explanations.empty()) << dg::diagnosis_summary(r);
  ASSERT_TRUE(r.tcp.present);
  for (double f : r.tcp.noise_floor_mm)
    EXPECT_GT(f, 1e-5) << dg::diagnosis_summary(r);
}

// The flat point of a planted bow at 0 mm, the X travel 0…90 mm: the
// reference is fitted with the quadratic term (held at the middle of the
// travel, the slope it leaves behind biased the quadratic term).
TEST(DiagnosisRecorders, StraightnessFlatPointAtTheEndOfTheTravel) {
  MachineDescription truth = believed_with_servo();
  truth.machine.effects.straightness.enabled = true;
  truth.machine.effects.straightness.params.components[kEYX] =
      StraightnessComponent{1500.0, 0.0, 0.0};
  RecordingSpec spec;
  spec.noise_mm = 0.001;
  const auto r = run(believed_with_servo(), make_recording(truth.machine, spec));
  const auto* e = find(r, "straightness", "eyx");
  ASSERT_NE(e, nullptr) << dg::diagnosis_summary(r);
  expect_covers(*e, "eyx.quadratic_um_per_m2", 1500.0, r);
  expect_covers(*e, "eyx.reference_mm", 0.0, r);
  EXPECT_EQ(r.explanations.size(), 1u) << dg::diagnosis_summary(r);
}

// A hand-made recording at 100 Hz: slow moves, one rapid out and back at
// 300 mm/s (ramps over several samples), and (second case) a one-sample jump to 198 mm and back.
Recording rapid_and_glitch(bool glitch) {
  Recording rec;
  rec.file = "rapid.csv";
  double x = 0;
  for (int k = 0; k < 2000; ++k) {
    const double t = k * 0.01;
    double v = (k / 100) % 2 == 0 ? 10.0 : -10.0;  // ±10 mm/s, reversing every second
    // A rapid out and back: up to 300 mm/s at 4000 mm/s² (7.5 samples), 20
    // samples at speed, down again.
    auto rapid = [](int i) {
      const double ramp = std::min({1.0, (i + 1) / 7.5, (35 - i) / 7.5});
      return i < 0 || i >= 35 ? 0.0 : 300.0 * std::max(0.0, ramp);
    };
    if (k >= 1000 && k < 1045) v = rapid(k - 1000);
    if (k >= 1045 && k < 1090) v = -rapid(k - 1045);
    x += v * 0.01;
    rec.t_s.push_back(t);
    const double cmd = glitch && k == 1500 ? 198.0 : x;
    rec.channels["x_cmd"].push_back(cmd);
    rec.channels["x_act"].push_back(cmd);
  }
  return rec;
}

TEST(DiagnosisRecorders, RapidMoveIsNoGlitchButAnIsolatedJumpIs) {
  MachineDescription d = xy_machine();
  dg::DiagnosisOptions o;
  o.holdout_fraction = 0;
  const auto clean = dg::diagnose(rapid_and_glitch(false), nullptr, d, o);
  EXPECT_EQ(clean.excluded_samples, 0u) << dg::diagnosis_summary(clean);
  const auto glitched = dg::diagnose(rapid_and_glitch(true), nullptr, d, o);
  EXPECT_GE(glitched.excluded_samples, 2u) << dg::diagnosis_summary(glitched);
  EXPECT_LE(glitched.excluded_samples, 4u) << dg::diagnosis_summary(glitched);
}

}  // namespace
}  // namespace truecut::analysis::test
