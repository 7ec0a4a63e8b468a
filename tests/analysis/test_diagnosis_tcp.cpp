// Trace mode with a measured tool-centre point (tcp_true_x/y/z): the rotary
// axis lines' location errors and the tool length, which joint traces alone
// cannot see. Recordings come from the simulator on a 5-axis motion of a
// trunnion machine (known servo lag on X and Y), the encoders read with
// σ = 0.2 µm noise, the TCP measured with σ = 1 µm.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "test_diagnosis_fixtures.hpp"
#include "truecut/analysis/diagnosis/diagnosis.hpp"
#include "truecut/analysis/recording.hpp"

namespace truecut::analysis::test {
using namespace truecut::sim;
using namespace truecut::sim::test;
namespace {

namespace dg = diagnosis;

dg::DiagnosisResult run(const MachineDescription& believed, const Recording& rec,
                        bool datum_known = false) {
  dg::DiagnosisOptions o;
  o.tcp_datum_known = datum_known;
  auto r = dg::diagnose(rec, nullptr, believed, o);
  if (std::getenv("TRUECUT_DIAGNOSIS_VERBOSE"))
    std::printf("%s\n", dg::diagnosis_summary(r).c_str());
  return r;
}

const dg::Explanation* find(const dg::DiagnosisResult& r, const std::string& effect) {
  for (const auto& e : r.explanations)
    if (e.effect == effect) return &e;
  return nullptr;
}

const dg::Parameter* param(const dg::Explanation& e, const std::string& name) {
  for (const auto& p : e.parameters)
    if (p.name == name) return &p;
  return nullptr;
}

bool names_pair(const dg::DiagnosisResult& r, const std::string& a, const std::string& b) {
  for (const auto& n : r.not_identifiable)
    if ((n.first == a && n.second == b) || (n.first == b && n.second == a)) return true;
  return false;
}

TEST(DiagnosisTcp, RotaryLocationFoundFromTheMeasuredTcp) {
  MachineDescription truth = trunnion_with_servo();
  auto& rl = truth.machine.effects.rotary_location;
  rl.enabled = true;
  rl.params.a.e_y0a_um = 8.0;
  rl.params.c.e_x0c_um = 10.0;
  rl.params.c.e_y0c_um = -6.0;
  const auto r = run(trunnion_with_servo(), five_axis_recording(truth.machine, 21));
  const auto s = dg::diagnosis_summary(r);
  ASSERT_TRUE(r.tcp.present) << s;
  const auto* e = find(r, "rotary_location");
  ASSERT_NE(e, nullptr) << s;
  EXPECT_EQ(find(r, "tool_length_error"), nullptr) << s;
  for (const auto& [name, value] : {std::pair<std::string, double>{"a.e_y0a_um", 8.0},
                                    {"c.e_x0c_um", 10.0},
                                    {"c.e_y0c_um", -6.0}}) {
    const auto* p = param(*e, name);
    ASSERT_NE(p, nullptr) << name << "\n" << s;
    EXPECT_LE(p->ci95_lo, value) << name << "\n" << s;
    EXPECT_GE(p->ci95_hi, value) << name << "\n" << s;
  }
  // Nothing else of the ten location parameters: only the planted three.
  EXPECT_EQ(e->parameters.size(), 3u) << s;
  ASSERT_GT(r.tcp.heldout.samples, 0u);
  EXPECT_LT(r.tcp.heldout.rms_after_mm, 0.5 * r.tcp.heldout.rms_before_mm) << s;
  EXPECT_LT(r.tcp.heldout.rms_after_mm, 1.2 * kTcpNoiseMm) << s;
  // The fitted description carries them.
  EXPECT_TRUE(r.fitted.machine.effects.rotary_location.enabled);
  EXPECT_NEAR(r.fitted.machine.effects.rotary_location.params.c.e_x0c_um, 10.0, 1.0);
}

// A longer tool and a Z offset of the A axis line move the TCP alike (up to
// a constant) at every A and C: with the measurement's offset unknown they
// cannot be told apart, and the diagnosis must say so, naming both.
TEST(DiagnosisTcp, ToolLengthAndAAxisZOffsetNotIdentifiableWithoutADatum) {
  MachineDescription truth = trunnion_with_servo();
  truth.machine.effects.tool_length_error.enabled = true;
  truth.machine.effects.tool_length_error.params.length_mm = 0.02;
  const auto r = run(trunnion_with_servo(), five_axis_recording(truth.machine, 22));
  const auto s = dg::diagnosis_summary(r);
  EXPECT_TRUE(names_pair(r, "tool_length_error", "rotary_location.a.e_z0a_um")) << s;
  // One of the two stands for both, and predicts the held-out block.
  EXPECT_TRUE(find(r, "tool_length_error") != nullptr || find(r, "rotary_location") != nullptr)
      << s;
  EXPECT_LT(r.tcp.heldout.rms_after_mm, 1.2 * kTcpNoiseMm) << s;
}

// Against a known datum the constant is no longer free: a tool-length error
// shifts the TCP at A = 0, an A-line offset does not. Told apart.
TEST(DiagnosisTcp, ToolLengthToldApartFromAAxisLocationWithAKnownDatum) {
  MachineDescription truth = trunnion_with_servo();
  truth.machine.effects.tool_length_error.enabled = true;
  truth.machine.effects.tool_length_error.params.length_mm = 0.02;
  const auto r = run(trunnion_with_servo(), five_axis_recording(truth.machine, 22), true);
  const auto s = dg::diagnosis_summary(r);
  const auto* e = find(r, "tool_length_error");
  ASSERT_NE(e, nullptr) << s;
  EXPECT_LE(e->parameters[0].ci95_lo, 0.02) << s;
  EXPECT_GE(e->parameters[0].ci95_hi, 0.02) << s;
  EXPECT_EQ(find(r, "rotary_location"), nullptr) << s;
  EXPECT_FALSE(names_pair(r, "tool_length_error", "rotary_location.a.e_z0a_um")) << s;
  EXPECT_LT(r.tcp.heldout.rms_after_mm, 0.5 * r.tcp.heldout.rms_before_mm) << s;
}

TEST(DiagnosisTcp, CorrectKinematicsSelectNothing) {
  const auto r = run(trunnion_with_servo(), five_axis_recording(trunnion_with_servo().machine, 23));
  const auto s = dg::diagnosis_summary(r);
  ASSERT_TRUE(r.tcp.present) << s;
  EXPECT_TRUE(r.explanations.empty()) << s;
  EXPECT_LT(r.tcp.train.rms_before_mm, 1.2 * kTcpNoiseMm) << s;
}

}  // namespace
}  // namespace truecut::analysis::test
