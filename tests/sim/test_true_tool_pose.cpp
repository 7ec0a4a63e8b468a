// The true tool pose: with every effect off it is the nominal forward
// kinematics; it follows the true joints and the slides' geometric errors;
// it is bit-for-bit repeatable.
#include <gtest/gtest.h>

#include <cstring>
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

void expect_near(const Eigen::Vector3d& want, const std::array<double, 3>& got, double tol,
                 const char* what) {
  for (int i = 0; i < 3; ++i)
    EXPECT_NEAR(want[i], got[i], tol) << what << " [" << i << "]";
}

AcJoints joints_of(const std::array<double, kJointCount>& p) {
  return {p[kX], p[kY], p[kZ], p[kA], p[kC]};
}

MachineParams random_kinematics(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-300.0, 300.0), len(0.0, 200.0);
  MachineParams m = ideal_params();
  KinematicsParams& k = m.kinematics;
  k.ac.x_rot_point_mm = u(rng);
  k.ac.y_rot_point_mm = u(rng);
  k.ac.z_rot_point_mm = u(rng);
  k.ac.y_offset_mm = u(rng) / 10;
  k.ac.z_offset_mm = u(rng) / 10;
  k.ac.conventional_directions = std::bernoulli_distribution(0.5)(rng);
  k.tool.length_mm = len(rng);
  return m;
}

}  // namespace

TEST(TrueToolPose, IdealMachineIsTheNominalForwardKinematics) {
  std::mt19937_64 rng(20261121);
  std::uniform_real_distribution<double> lin(-500.0, 500.0), a(-120.0, 120.0), c(-3600.0, 3600.0);
  for (int trial = 0; trial < 2000; ++trial) {
    const MachineParams m = random_kinematics(rng);
    const AcJoints j{lin(rng), lin(rng), lin(rng), a(rng), c(rng)};
    const ToolPose want = forward_ac(nominal_ac_params(m), j);
    const ToolPose got =
        true_tool_pose(true_kinematics(m), {j.x_mm, j.y_mm, j.z_mm}, j.a_deg, j.c_deg);
    ASSERT_LT((want.tcp_mm - got.tcp_mm).norm(), 1e-12) << "trial " << trial;
    ASSERT_LT((want.axis - got.axis).norm(), 1e-12) << "trial " << trial;
  }
}

TEST(TrueToolPose, NominalParamsCarryPivotsToolAndATravel) {
  MachineParams m = trunnion_params(true);
  m.joints[kA].min = -110.0;
  m.joints[kA].max = 20.0;
  const auto p = nominal_ac_params(m);
  EXPECT_EQ(120.0, p.x_rot_point_mm);
  EXPECT_EQ(-40.0, p.y_rot_point_mm);
  EXPECT_EQ(-250.0, p.z_rot_point_mm);
  EXPECT_EQ(30.0, p.y_offset_mm);
  EXPECT_EQ(60.0, p.z_offset_mm);
  EXPECT_EQ(80.0, p.tool_length_mm);
  EXPECT_TRUE(p.conventional_directions);
  EXPECT_EQ(-110.0, p.a_min_deg);
  EXPECT_EQ(20.0, p.a_max_deg);
}

TEST(TrueToolPose, ModelOutputsTheNominalPoseWhenEveryEffectIsOff) {
  for (bool conventional : {false, true}) {
    MachineParams m = trunnion_params(conventional);
    // Parameters present but switched off change nothing.
    m.effects.rotary_location.params.c.e_x0c_um = 30.0;
    m.effects.tool_length_error.params.length_mm = 0.2;
    auto tr = run(m, 1e-3, 500, [](double t) {
      MachineInputs in;
      in.pos_cmd = {100.0 * std::sin(t), 50.0 * std::cos(2 * t), -20.0 * t, 40.0 * std::sin(3 * t),
                    720.0 * t};
      return in;
    });
    const auto nominal = nominal_ac_params(m);
    for (size_t k = 0; k < tr.out.size(); ++k) {
      const ToolPose want = forward_ac(nominal, joints_of(tr.in[k].pos_cmd));
      for (int i = 0; i < 3; ++i) {
        ASSERT_NEAR(want.tcp_mm[i], tr.out[k].tcp_true[i], 1e-12) << "cycle " << k;
        ASSERT_NEAR(want.axis[i], tr.out[k].tool_axis_true[i], 1e-12) << "cycle " << k;
      }
    }
  }
}

TEST(TrueToolPose, FollowsTheTrueJointsAndTheSlidesGeometricErrors) {
  MachineParams m = trunnion_params();
  m.effects.squareness = {true, {200.0, 0.0, 0.0}};
  m.effects.backlash.enabled = true;
  m.effects.backlash.axes[kC] = BacklashAxis{0.05};
  auto tr = run(m, 1e-3, 400, [](double t) {
    MachineInputs in;
    in.pos_cmd = {150.0, 80.0, -100.0, 30.0, 90.0 * std::sin(5 * t)};
    return in;
  });
  const auto nominal = nominal_ac_params(m);
  const auto& out = tr.out.back();
  // The pose is the true kinematics of the true positions, not of the commands.
  const ToolPose want = forward_ac(nominal, {out.xyz_true[0], out.xyz_true[1], out.xyz_true[2],
                                             out.pos_true[kA], out.pos_true[kC]});
  expect_near(want.tcp_mm, out.tcp_true, 1e-12, "tcp");
  expect_near(want.axis, out.tool_axis_true, 1e-12, "axis");
  EXPECT_NEAR(150.0 + 200e-6 * 80.0, out.xyz_true[0], 1e-12) << "squareness reached xyz";
  EXPECT_GT(std::abs(out.pos_true[kC] - tr.in.back().pos_cmd[kC]), 0.02) << "backlash on C";
  const ToolPose commanded = forward_ac(nominal, joints_of(tr.in.back().pos_cmd));
  EXPECT_GT((commanded.tcp_mm - want.tcp_mm).norm(), 0.01);
}

TEST(TrueToolPose, DefaultModelIsIdealWithZeroPivots) {
  MachineModel model;
  MachineState state;
  MachineInputs in;
  in.pos_cmd = {10.0, 20.0, 30.0, 90.0, 0.0};
  MachineOutputs out;
  model.step(state, in, 1e-3, out);
  // A = 90: the table's +Y face turns up; the spindle at (10, 20, 30) is at
  // (10, 30, -20) in the workpiece frame, the tool axis along +Y.
  expect_near(Eigen::Vector3d(10.0, 30.0, -20.0), out.tcp_true, 1e-12, "tcp");
  expect_near(Eigen::Vector3d(0.0, 1.0, 0.0), out.tool_axis_true, 1e-15, "axis");
}

TEST(TrueToolPose, TwoRunsWithEveryPoseEffectAreBitIdentical) {
  MachineParams m = trunnion_params();
  for (int j = 0; j < kJointCount; ++j)
    enable_servo_lag(m, j, 30.0, 0.7);
  m.effects.backlash.enabled = true;
  m.effects.backlash.axes[kA] = BacklashAxis{0.003};
  m.effects.squareness = {true, {20.0, -10.0, 5.0}};
  m.effects.rotary_location = {true,
                               {{12.0, -8.0, 30.0, -20.0, 50.0}, {5.0, 7.0, -15.0, 25.0, -40.0}}};
  m.effects.tool_length_error = {true, {0.03}};
  auto path = [](double t) {
    MachineInputs in;
    in.pos_cmd = {80.0 * std::sin(t), 60.0 * std::sin(1.3 * t), -30.0 * std::cos(0.7 * t),
                  45.0 * std::sin(0.9 * t), 200.0 * t};
    return in;
  };
  auto a = run(m, 250e-6, 8000, path);
  auto b = run(m, 250e-6, 8000, path);
  double dev = 0.0;
  const auto nominal = nominal_ac_params(m);
  for (size_t k = 0; k < a.out.size(); ++k) {
    ASSERT_EQ(0, std::memcmp(a.out[k].tcp_true.data(), b.out[k].tcp_true.data(), 24)) << k;
    ASSERT_EQ(0, std::memcmp(a.out[k].tool_axis_true.data(), b.out[k].tool_axis_true.data(), 24));
    const ToolPose commanded = forward_ac(nominal, joints_of(a.in[k].pos_cmd));
    dev = std::max(dev, (commanded.tcp_mm - Eigen::Vector3d(a.out[k].tcp_true.data())).norm());
  }
  EXPECT_GT(dev, 1e-3) << "the effects did something";
}
