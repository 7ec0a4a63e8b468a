// Diagnosis on recordings generated with the simulator: one effect planted
// near the noise level under a known effect of the believed model must be
// named, fitted (interval covering the truth) and must bring the held-out
// residual down to the noise; negative controls select nothing.
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

std::string describe(const dg::DiagnosisResult& r) {
  return dg::diagnosis_summary(r);
}

// Held-out RMS after the fit near the noise the recording was made with.
void expect_heldout_at_noise(const dg::DiagnosisResult& r, double noise_mm) {
  ASSERT_TRUE(r.has_heldout);
  EXPECT_LT(r.heldout.rms_after_mm, 1.5 * noise_mm) << describe(r);
  EXPECT_LT(r.heldout.rms_after_mm, 1.5 * r.noise_floor_mm) << describe(r);
  EXPECT_LT(r.heldout.rms_after_mm, r.heldout.rms_before_mm) << describe(r);
}

void expect_only(const dg::DiagnosisResult& r, const std::string& effect) {
  for (const auto& e : r.explanations)
    EXPECT_EQ(e.effect, effect) << describe(r);
}

TEST(Diagnosis, BacklashUnderKnownServo) {
  MachineDescription truth = believed_with_servo();
  truth.machine.effects.backlash.enabled = true;
  truth.machine.effects.backlash.axes[kX] = BacklashAxis{0.004};
  RecordingSpec spec;
  spec.noise_mm = 0.0015;
  const auto r = run(believed_with_servo(), make_recording(truth.machine, spec));
  const auto* e = find(r, "backlash", "x");
  ASSERT_NE(e, nullptr) << describe(r);
  expect_covers(*e, "play_mm", 0.004, r);
  expect_only(r, "backlash");  // not reversal_spike: the dwells tell them apart
  expect_heldout_at_noise(r, spec.noise_mm);
}

TEST(Diagnosis, PitchErrorUnderKnownServo) {
  MachineDescription truth = believed_with_servo();
  truth.machine.effects.pitch_error.enabled = true;
  PitchErrorAxis pe;
  pe.scale_um_per_m = 30;
  pe.periodic_amplitude_um = 1.5;
  pe.periodic_period_mm = 10;
  pe.periodic_phase_deg = 40;
  truth.machine.effects.pitch_error.axes[kY] = pe;
  RecordingSpec spec;
  spec.noise_mm = 0.001;
  const auto r = run(believed_with_servo(), make_recording(truth.machine, spec));
  const dg::Explanation* scale = nullptr;
  const dg::Explanation* periodic = nullptr;
  for (const auto& e : r.explanations)
    if (e.effect == "pitch_error" && e.axis == "y")
      (param(e, "scale_um_per_m") ? scale : periodic) = &e;
  ASSERT_NE(scale, nullptr) << describe(r);
  ASSERT_NE(periodic, nullptr) << describe(r);
  expect_covers(*scale, "scale_um_per_m", 30, r);
  expect_covers(*periodic, "periodic_amplitude_um", 1.5, r);
  expect_covers(*periodic, "periodic_period_mm", 10, r);
  expect_only(r, "pitch_error");
  expect_heldout_at_noise(r, spec.noise_mm);
}

TEST(Diagnosis, ThermalDriftUnderKnownServo) {
  MachineDescription truth = believed_with_servo();
  truth.machine.effects.thermal_drift.enabled = true;
  ThermalDriftAxis th;
  th.gain_mm = 0.006;
  th.tau_s = 4.0;
  truth.machine.effects.thermal_drift.axes[kX] = th;
  RecordingSpec spec;
  spec.noise_mm = 0.0015;
  const auto r = run(believed_with_servo(), make_recording(truth.machine, spec));
  const auto* e = find(r, "thermal_drift", "x");
  ASSERT_NE(e, nullptr) << describe(r);
  expect_covers(*e, "gain_mm", 0.006, r);
  expect_covers(*e, "tau_s", 4.0, r);
  expect_only(r, "thermal_drift");
  expect_heldout_at_noise(r, spec.noise_mm);
}

TEST(Diagnosis, SquarenessUnderKnownServo) {
  MachineDescription truth = believed_with_servo();
  truth.machine.effects.squareness.enabled = true;
  truth.machine.effects.squareness.params.xy_urad = 40;
  RecordingSpec spec;
  spec.noise_mm = 0.001;
  const auto r = run(believed_with_servo(), make_recording(truth.machine, spec));
  const auto* e = find(r, "squareness", "xy");
  ASSERT_NE(e, nullptr) << describe(r);
  expect_covers(*e, "xy_urad", 40, r);
  expect_only(r, "squareness");
  expect_heldout_at_noise(r, spec.noise_mm);
}

TEST(Diagnosis, ReversalSpikeUnderKnownServo) {
  MachineDescription truth = believed_with_servo();
  truth.machine.effects.reversal_spike.enabled = true;
  truth.machine.effects.reversal_spike.axes[kX] = ReversalSpikeAxis{80.0, 0.0};
  RecordingSpec spec;
  spec.noise_mm = 0.0005;
  spec.meas = false;  // the encoder sees the friction spike
  const auto r = run(believed_with_servo(), make_recording(truth.machine, spec));
  const auto* e = find(r, "reversal_spike", "x");
  ASSERT_NE(e, nullptr) << describe(r);
  expect_covers(*e, "coulomb_n", 80.0, r);
  expect_only(r, "reversal_spike");
  expect_heldout_at_noise(r, spec.noise_mm);
}

TEST(Diagnosis, ServoLagUnderKnownBacklash) {
  // Believed: backlash on X known, no servo model at all (actual = commanded).
  MachineDescription believed = xy_machine();
  believed.machine.effects.backlash.enabled = true;
  believed.machine.effects.backlash.axes[kX] = BacklashAxis{0.003};
  MachineDescription truth = believed;
  enable_servo_lag(truth.machine, kX, 50.0, 0.95);
  RecordingSpec spec;
  spec.noise_mm = 0.001;
  const auto r = run(believed, make_recording(truth.machine, spec));
  const auto* e = find(r, "servo_lag", "x");
  ASSERT_NE(e, nullptr) << describe(r);
  expect_covers(*e, "kv_per_s", 50.0, r);
  expect_covers(*e, "ff1", 0.95, r);
  expect_only(r, "servo_lag");
  EXPECT_NEAR(r.delay_s, 0.0, 2e-4) << describe(r);
  expect_heldout_at_noise(r, spec.noise_mm);
}

TEST(Diagnosis, LoggingDelayIsNotServoLag) {
  // The believed model is right; the recorder logs the positions 4 ms late.
  const MachineDescription believed = believed_with_servo();
  RecordingSpec spec;
  spec.noise_mm = 0.001;
  spec.logging_delay_s = 0.004;
  spec.duration_s = 6;
  const auto r = run(believed, make_recording(believed.machine, spec));
  // With 1 kHz data and sharp trapezoids the delay is told apart from a servo lag.
  for (const auto& n : r.not_identifiable)
    EXPECT_NE(n.first, "logging_delay") << describe(r);
  EXPECT_NEAR(r.delay_s, 0.004, 2e-4) << describe(r);
  ASSERT_TRUE(r.delay_ci95_s);
  EXPECT_LE(r.delay_ci95_s->first, 0.004) << describe(r);
  EXPECT_GE(r.delay_ci95_s->second, 0.004) << describe(r);
  EXPECT_TRUE(r.explanations.empty()) << describe(r);
  EXPECT_LT(r.train.rms_before_mm, 1.5 * spec.noise_mm) << describe(r);
  EXPECT_GT(r.train.rms_unaligned_mm, 3 * spec.noise_mm) << describe(r);
}

TEST(Diagnosis, PureNoiseSelectsNothing) {
  const MachineDescription believed = xy_machine();
  RecordingSpec spec;
  spec.noise_mm = 0.002;
  spec.duration_s = 8;
  const auto r = run(believed, make_recording(believed.machine, spec));
  EXPECT_TRUE(r.explanations.empty()) << describe(r);
  EXPECT_EQ(r.verdict.rfind("nothing missing", 0), 0u) << describe(r);
  EXPECT_NEAR(r.noise_floor_mm, spec.noise_mm, 0.2 * spec.noise_mm) << describe(r);
  EXPECT_NEAR(r.delay_s, 0.0, 1e-3);
}

TEST(Diagnosis, CorrectBelievedModelSelectsNothing) {
  MachineDescription believed = believed_with_servo();
  believed.machine.effects.backlash.enabled = true;
  believed.machine.effects.backlash.axes[kX] = BacklashAxis{0.005};
  believed.machine.effects.squareness.enabled = true;
  believed.machine.effects.squareness.params.xy_urad = 30;
  RecordingSpec spec;
  spec.noise_mm = 0.001;
  spec.duration_s = 8;
  spec.seed = 7;
  const auto r = run(believed, make_recording(believed.machine, spec));
  EXPECT_TRUE(r.explanations.empty()) << describe(r);
  EXPECT_TRUE(r.mismatch.empty()) << describe(r);
  EXPECT_EQ(r.fitted.machine, believed.machine);
}

TEST(Diagnosis, HoldoutRecordingProvesTheFit) {
  MachineDescription truth = believed_with_servo();
  truth.machine.effects.backlash.enabled = true;
  truth.machine.effects.backlash.axes[kY] = BacklashAxis{0.005};
  RecordingSpec spec;
  spec.noise_mm = 0.001;
  spec.duration_s = 8;
  const auto train = make_recording(truth.machine, spec);
  spec.seed = 2;
  const auto held = make_recording(truth.machine, spec, 1);
  dg::DiagnosisOptions o;
  const auto r = dg::diagnose(train, &held, believed_with_servo(), o);
  ASSERT_NE(find(r, "backlash", "y"), nullptr) << describe(r);
  EXPECT_EQ(r.heldout_kind, "file");
  expect_heldout_at_noise(r, spec.noise_mm);
  // The fitted description re-reads to the same parameters.
  const auto text = format_machine_description(r.fitted);
  const auto back = parse_machine_description(text, "fitted_machine.json");
  ASSERT_TRUE(back.machine.effects.backlash.active(kY));
  EXPECT_NEAR(back.machine.effects.backlash.axes[kY]->play, 0.005, 0.001);
}

}  // namespace
}  // namespace truecut::analysis::test
