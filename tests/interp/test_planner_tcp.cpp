// TCP mode (TRAORI): rotaries interpolated with the TCP path, joints from
// inverse_ac, no C spin at the A = 0 singularity.
#include "planner_test_util.hpp"

namespace truecut::interp::testing {
namespace {

PlannerOptions with_pivots() {
  PlannerOptions o;
  o.kinematics.x_rot_point_mm = 2;
  o.kinematics.y_rot_point_mm = 10;
  o.kinematics.z_offset_mm = 40;
  return o;
}

double max_step(const std::vector<CycleOutput>& s, int joint) {
  double m = 0;
  for (size_t n = 1; n < s.size(); ++n)
    m = std::max(m, std::abs(s[n].joints[joint] - s[n - 1].joints[joint]));
  return m;
}

TEST(PlannerTcp, CrossingAZeroKeepsC) {
  const PlannerOptions o = with_pivots();
  const auto s = sample_plan(
      plan_text("G0 X0 Y0 Z30 A-20 C35\nTRAORI\nG1 X40 A20 F900\nTRAFOOF\nM2\n", o), 0.001);
  bool crossed = false;
  for (const auto& c : s) {
    if (!c.tcp_mode) continue;
    EXPECT_NEAR(35.0, c.joints[kAxisC], 1e-9);
    crossed = crossed || std::abs(c.joints[kAxisA]) < 0.05;
  }
  EXPECT_TRUE(crossed);
  EXPECT_TRUE(check_limits(s, o.limits, o.servo_period_s).ok());
}

TEST(PlannerTcp, LeavingTheVerticalTurnsCWithinItsLimits) {
  // From A0 C0 to A10 C90: C is undefined at the start, but the interpolated
  // angles turn it smoothly; a tool-axis interpolation would ask for a C jump.
  const PlannerOptions o = with_pivots();
  const auto s = sample_plan(
      plan_text("G0 X0 Y0 Z30 A0 C0\nTRAORI\nG1 X5 A10 C90 F300\nTRAFOOF\nM2\n", o), 0.001);
  EXPECT_LE(max_step(s, kAxisC), o.limits.axis[kAxisC].max_velocity * 0.001 + 1e-9);
  EXPECT_NEAR(90.0, s.back().joints[kAxisC], 1e-9);
  EXPECT_TRUE(check_limits(s, o.limits, o.servo_period_s).ok());
}

TEST(PlannerTcp, PoseMatchesTheKinematics) {
  // What the cycle reports is consistent: forward(joints) = (TCP, axis).
  const PlannerOptions o = with_pivots();
  const auto s = sample_plan(
      plan_text("G0 X0 Y0 Z30\nTRAORI\nG1 X10 Y5 Z20 A25 C-60 F600\nG1 X-5 A-15 C20\nTRAFOOF\nM2\n",
                o),
      0.001);
  rt::AcTrtParams kin = o.kinematics;
  for (size_t n = 0; n < s.size(); n += 97) {
    const auto& c = s[n];
    const rt::ToolPose pose =
        rt::forward_ac(kin, {c.joints[0], c.joints[1], c.joints[2], c.joints[3], c.joints[4]});
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(pose.tcp_mm[i], c.tcp_mm[i], 1e-9) << n;
      EXPECT_NEAR(pose.axis[i], c.tool_axis[i], 1e-12) << n;
    }
  }
}

TEST(PlannerTcp, SwitchingTcpKeepsTheJointsContinuous) {
  const PlannerOptions o = with_pivots();
  const auto s = sample_plan(
      plan_text("G0 X10 Y0 Z30 A15 C30\nTRAORI\nG1 X12 F600\nTRAFOOF\nG1 X0\nM2\n", o), 0.001);
  for (int j = 0; j < 5; ++j)
    EXPECT_LE(max_step(s, j), o.limits.axis[j].max_velocity * 0.001 + 1e-9) << j;
  EXPECT_TRUE(check_limits(s, o.limits, o.servo_period_s).ok());
}

TEST(PlannerTcp, FiveAxisDemosHaveNoCSpin) {
  std::string why;
  const auto share = linuxcnc_share(why);
  if (!share) TRUECUT_ORACLE_MISSING(rs274_missing(why));
  const PlannerOptions o = with_pivots();
  for (const char* name : {"boat-xyzac.ngc", "impeller-7bl-xyzac.ngc"})
    for (bool tcp : {false, true}) {
      const auto s =
          sample_plan(plan_program(run(demo_text(five_axis_demo(*share, name), tcp)), o), 0.001);
      EXPECT_LE(max_step(s, kAxisC), o.limits.axis[kAxisC].max_velocity * 0.001 + 1e-9) << name;
    }
}

}  // namespace
}  // namespace truecut::interp::testing
