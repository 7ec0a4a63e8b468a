// tool_length_error moves the true TCP along the tool axis by the set
// length at any A and C; tool_radius_error changes the true cutter, not the
// pose.
#include <gtest/gtest.h>

#include <random>

#include "machine_fixtures.hpp"
#include "truecut/rt/core/kinematics_ac.hpp"
#include "truecut/sim/true_tool_pose.hpp"

using namespace truecut::sim;
using namespace truecut::sim::test;
using truecut::rt::AcJoints;
using truecut::rt::forward_ac;
using truecut::rt::ToolPose;

namespace {

ToolPose pose_of(const MachineParams& m, const AcJoints& j) {
  return true_tool_pose(true_kinematics(m), {j.x_mm, j.y_mm, j.z_mm}, j.a_deg, j.c_deg);
}

MachineParams with_radius_error(NominalTool tool, double radius_mm, double corner_mm) {
  MachineParams m = trunnion_params();
  m.kinematics.tool = tool;
  m.effects.tool_radius_error = {true, {radius_mm, corner_mm}};
  return m;
}

void expect_tool(const TrueTool& want, const TrueTool& got) {
  EXPECT_DOUBLE_EQ(want.length_mm, got.length_mm);
  EXPECT_DOUBLE_EQ(want.radius_mm, got.radius_mm);
  EXPECT_DOUBLE_EQ(want.corner_radius_mm, got.corner_radius_mm);
}

}  // namespace

TEST(ToolLengthError, ShiftsTheTcpAlongTheToolAxisAtAnyAngle) {
  std::mt19937_64 rng(4711);
  std::uniform_real_distribution<double> lin(-300.0, 300.0), a(-120.0, 120.0), c(-720.0, 720.0);
  for (bool conventional : {false, true}) {
    for (double dl : {0.05, -0.2}) {
      MachineParams m = trunnion_params(conventional);
      m.effects.tool_length_error = {true, {dl}};
      const auto nominal = nominal_ac_params(m);
      for (int trial = 0; trial < 500; ++trial) {
        const AcJoints j{lin(rng), lin(rng), lin(rng), a(rng), c(rng)};
        const ToolPose want = forward_ac(nominal, j);
        const ToolPose got = pose_of(m, j);
        // A longer tool reaches further from the spindle: −ΔL along the axis.
        ASSERT_LT((got.tcp_mm - (want.tcp_mm - dl * want.axis)).norm(), 1e-11) << trial;
        ASSERT_LT((got.axis - want.axis).norm(), 1e-15);
      }
    }
  }
}

TEST(ToolLengthError, ChangesTheTrueToolLengthAndNothingWhenOff) {
  MachineParams m = trunnion_params();
  m.effects.tool_length_error = {false, {0.3}};
  EXPECT_EQ(80.0, true_tool(m).length_mm);
  const AcJoints j{10.0, 20.0, 30.0, 40.0, 50.0};
  EXPECT_EQ(pose_of(trunnion_params(), j).tcp_mm, pose_of(m, j).tcp_mm);
  m.effects.tool_length_error.enabled = true;
  EXPECT_DOUBLE_EQ(80.3, true_tool(m).length_mm);
  EXPECT_EQ(80.0, nominal_ac_params(m).tool_length_mm) << "the controller keeps the nominal tool";
}

TEST(ToolRadiusError, ChangesTheTrueCutterNotThePose) {
  // The model-adaptation source: CAM assumed a ball end mill 0.2 mm larger
  // in diameter than the real one.
  const MachineParams ball = with_radius_error({80.0, 3.0, 3.0}, -0.1, 0.0);
  expect_tool(TrueTool{80.0, 2.9, 2.9}, true_tool(ball));
  const MachineParams flat = with_radius_error({80.0, 5.0, 0.0}, 0.02, 0.0);
  expect_tool(TrueTool{80.0, 5.02, 0.0}, true_tool(flat));
  const MachineParams bull = with_radius_error({80.0, 5.0, 1.0}, -0.05, 0.01);
  expect_tool(TrueTool{80.0, 4.95, 1.01}, true_tool(bull));

  const AcJoints j{10.0, 20.0, 30.0, -35.0, 123.0};
  const ToolPose nominal = pose_of(trunnion_params(), j);
  for (const auto* m : {&ball, &flat, &bull}) {
    EXPECT_EQ(nominal.tcp_mm, pose_of(*m, j).tcp_mm);
    EXPECT_EQ(nominal.axis, pose_of(*m, j).axis);
  }
  MachineParams off = ball;
  off.effects.tool_radius_error.enabled = false;
  expect_tool(TrueTool{80.0, 3.0, 3.0}, true_tool(off));
}

TEST(ToolErrors, ModelExposesTheTrueTool) {
  MachineParams m = trunnion_params();
  m.kinematics.tool = {60.0, 4.0, 4.0};
  m.effects.tool_length_error = {true, {-0.02}};
  m.effects.tool_radius_error = {true, {0.1, 0.0}};
  const MachineModel model(m);
  expect_tool(TrueTool{59.98, 4.1, 4.1}, model.true_tool());
}
