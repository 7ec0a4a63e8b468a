// Trace mode, the candidates added after the first set: straightness, a
// thermal drift driven by the recorded spindle power, and the confusable
// pair squareness vs servo mismatch (a servo loop that differs from the
// believed one must not be taken for squareness).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "test_diagnosis_checks.hpp"
#include "test_diagnosis_fixtures.hpp"

namespace truecut::analysis::test {
using namespace truecut::sim;
using namespace truecut::sim::test;
namespace {

namespace dg = diagnosis;

// Spindle power of the synthetic job: off, a heavy cut, a light cut.
double power_kw(double t) {
  return t < 2.0 ? 0.0 : t < 7.0 ? 8.0 : 2.0;
}

// As make_recording, with a spindle_power channel driving the model.
Recording powered_recording(const MachineParams& truth, double noise_mm, unsigned seed) {
  const MovePath px = default_x_path(), py = default_y_path();
  const double dt = 1e-3;
  const int n = 12000;
  MachineModel model(truth);
  MachineState state;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_mm);
  Recording rec;
  rec.file = "powered.csv";
  for (const char* c : {"x_cmd", "y_cmd", "x_act", "y_act", "x_meas", "y_meas", "spindle_power"})
    rec.channels[c];
  for (int k = 0; k < n; ++k) {
    const double t = k * dt;
    MachineInputs in;
    in.pos_cmd[kX] = px.at(t);
    in.pos_cmd[kY] = py.at(t);
    in.spindle_power_kw = power_kw(t);
    MachineOutputs out;
    model.step(state, in, dt, out);
    rec.t_s.push_back(t);
    rec.channels["x_cmd"].push_back(in.pos_cmd[kX]);
    rec.channels["y_cmd"].push_back(in.pos_cmd[kY]);
    rec.channels["x_act"].push_back(out.pos_act[kX]);
    rec.channels["y_act"].push_back(out.pos_act[kY]);
    rec.channels["x_meas"].push_back(out.xyz_true[kX] + noise(rng));
    rec.channels["y_meas"].push_back(out.xyz_true[kY] + noise(rng));
    rec.channels["spindle_power"].push_back(in.spindle_power_kw);
  }
  return rec;
}

void expect_only(const dg::DiagnosisResult& r, const std::string& effect) {
  for (const auto& e : r.explanations)
    EXPECT_EQ(e.effect, effect) << dg::diagnosis_summary(r);
}

TEST(DiagnosisTraceEffects, StraightnessUnderKnownServo) {
  // Y bows with X, about the middle of the X travel the recording covers
  // (ISO 230-1: straightness is measured against the straight line through
  // the travel; a linear part of the bow would be squareness / alignment).
  RecordingSpec spec;
  const MovePath px = default_x_path();
  double lo = 1e9, hi = -1e9;
  for (int k = 0; k < int(spec.duration_s / spec.period_s); ++k)
    lo = std::min(lo, px.at(k * spec.period_s)), hi = std::max(hi, px.at(k * spec.period_s));
  MachineDescription truth = believed_with_servo();
  truth.machine.effects.straightness.enabled = true;
  truth.machine.effects.straightness.params.components[kEYX] =
      StraightnessComponent{2000.0, 0.0, std::round((lo + hi) / 2 * 1000) / 1000};
  spec.noise_mm = 0.001;
  const auto r = run(believed_with_servo(), make_recording(truth.machine, spec));
  const auto* e = find(r, "straightness", "eyx");
  ASSERT_NE(e, nullptr) << dg::diagnosis_summary(r);
  expect_covers(*e, "eyx.quadratic_um_per_m2", 2000.0, r);
  expect_only(r, "straightness");
  ASSERT_TRUE(r.has_heldout);
  EXPECT_LT(r.heldout.rms_after_mm, 1.5 * spec.noise_mm) << dg::diagnosis_summary(r);
}

TEST(DiagnosisTraceEffects, ThermalDriftDrivenBySpindlePower) {
  MachineDescription truth = believed_with_servo();
  truth.machine.effects.thermal_drift.enabled = true;
  ThermalDriftAxis th;
  th.gain_mm = 0.008;
  th.tau_s = 3.0;
  th.driver = ThermalDriver::kSpindlePower;
  th.reference_power_kw = 10.0;
  truth.machine.effects.thermal_drift.axes[kX] = th;
  const auto r = run(believed_with_servo(), powered_recording(truth.machine, 0.001, 3));
  const auto* e = find(r, "thermal_drift", "x");
  ASSERT_NE(e, nullptr) << dg::diagnosis_summary(r);
  expect_covers(*e, "gain_mm", 0.008, r);
  expect_covers(*e, "tau_s", 3.0, r);
  expect_only(r, "thermal_drift");
  ASSERT_TRUE(r.fitted.machine.effects.thermal_drift.axes[kX]);
  EXPECT_EQ(r.fitted.machine.effects.thermal_drift.axes[kX]->driver, ThermalDriver::kSpindlePower);
  ASSERT_TRUE(r.has_heldout);
  EXPECT_LT(r.heldout.rms_after_mm, 1.5 * 0.001) << dg::diagnosis_summary(r);
}

TEST(DiagnosisTraceEffects, ServoMismatchIsNotSquareness) {
  // The real X loop is slower than believed: a lag that grows with the
  // speed, on a path where X and Y move independently (so squareness, which
  // grows with Y's position, is told apart).
  MachineDescription truth = believed_with_servo();
  truth.machine.effects.servo_lag.axes[kX] = ServoLagAxis{30.0, 0.9};
  RecordingSpec spec;
  spec.noise_mm = 0.001;
  const auto r = run(believed_with_servo(), make_recording(truth.machine, spec));
  const auto* e = find(r, "servo_lag", "x");
  ASSERT_NE(e, nullptr) << dg::diagnosis_summary(r);
  expect_covers(*e, "kv_per_s", 30.0, r);
  EXPECT_EQ(find(r, "squareness", "xy"), nullptr) << dg::diagnosis_summary(r);
}

}  // namespace
}  // namespace truecut::analysis::test
