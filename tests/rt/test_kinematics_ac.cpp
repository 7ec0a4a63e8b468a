#include "truecut/rt/core/kinematics_ac.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <utility>

namespace truecut::rt {
namespace {

static_assert(noexcept(forward_ac(AcTrtParams{}, AcJoints{})));
static_assert(noexcept(inverse_ac(AcTrtParams{}, std::declval<const ToolPose&>(), AcJoints{})));

constexpr double kTol = 1e-9;

void expect_pose_near(const ToolPose& actual, const Eigen::Vector3d& tcp_mm,
                      const Eigen::Vector3d& axis, double tol) {
  EXPECT_LE((actual.tcp_mm - tcp_mm).cwiseAbs().maxCoeff(), tol)
      << "tcp " << actual.tcp_mm.transpose() << " expected " << tcp_mm.transpose();
  EXPECT_LE((actual.axis - axis).cwiseAbs().maxCoeff(), tol)
      << "axis " << actual.axis.transpose() << " expected " << axis.transpose();
}

double max_joint_error(const AcJoints& a, const AcJoints& b) {
  return std::max({std::abs(a.x_mm - b.x_mm), std::abs(a.y_mm - b.y_mm), std::abs(a.z_mm - b.z_mm),
                   std::abs(a.a_deg - b.a_deg), std::abs(a.c_deg - b.c_deg)});
}

// --- hand-computed poses -------------------------------------------------

TEST(KinematicsAc, HomeIsIdentity) {
  const ToolPose pose = forward_ac({}, {10, 20, 30, 0, 0});
  expect_pose_near(pose, {10, 20, 30}, {0, 0, 1}, 1e-12);
}

TEST(KinematicsAc, A90TurnsWorkpiecePlusYTowardsSpindle) {
  // Table tilted +90 deg about X: the workpiece's +Y now points up (machine +Z).
  const ToolPose pose = forward_ac({}, {0, 0, 100, 90, 0});
  expect_pose_near(pose, {0, 100, 0}, {0, 1, 0}, 1e-12);
}

TEST(KinematicsAc, C90) {
  // Table turned +90 deg about Z: workpiece point (0, -100, 0) lies at machine (100, 0, 0).
  const ToolPose pose = forward_ac({}, {100, 0, 0, 0, 90});
  expect_pose_near(pose, {0, -100, 0}, {0, 0, 1}, 1e-12);
}

TEST(KinematicsAc, A90C90) {
  const ToolPose pose = forward_ac({}, {0, 0, 100, 90, 90});
  expect_pose_near(pose, {100, 0, 0}, {1, 0, 0}, 1e-12);
}

TEST(KinematicsAc, ConventionalDirectionsReverseBothAxes) {
  AcTrtParams p;
  p.conventional_directions = true;
  expect_pose_near(forward_ac(p, {0, 0, 100, 90, 0}), {0, -100, 0}, {0, -1, 0}, 1e-12);
  expect_pose_near(forward_ac(p, {100, 0, 0, 0, 90}), {0, 100, 0}, {0, 0, 1}, 1e-12);
}

TEST(KinematicsAc, PivotOffsetsAndToolLength) {
  // C axis through (10, 20); A axis at y = 20, z = -100; 50 mm tool. The TCP
  // sits 100 mm above the A axis; tilting 90 deg puts it 100 mm along +Y of
  // the A axis, at the A axis height.
  AcTrtParams p;
  p.x_rot_point_mm = 10;
  p.y_rot_point_mm = 20;
  p.z_offset_mm = -100;
  p.tool_length_mm = 50;
  expect_pose_near(forward_ac(p, {10, 20, 50, 90, 0}), {10, 120, -100}, {0, 1, 0}, 1e-12);
  // Only z_rot_point + z_offset matters.
  p.z_rot_point_mm = 40;
  p.z_offset_mm = -140;
  expect_pose_near(forward_ac(p, {10, 20, 50, 90, 0}), {10, 120, -100}, {0, 1, 0}, 1e-12);
}

TEST(KinematicsAc, MatchesLinuxCncWorldMinusToolLength) {
  // Reference: xyzac-trt-kins' forward equations evaluated for these pins
  // (x/y/z-rot-point 1/2/5, y-offset 3, z-offset 11, tool-offset 7) and joints
  // (10, 20, 30, 15, 25); its world Z includes the tool offset.
  AcTrtParams p;
  p.x_rot_point_mm = 1;
  p.y_rot_point_mm = 2;
  p.z_rot_point_mm = 5;
  p.y_offset_mm = 3;
  p.z_offset_mm = 11;
  p.tool_length_mm = 7;
  const AcJoints j{10, 20, 30, 15, 25};
  const double a = 15 * M_PI / 180, c = 25 * M_PI / 180;
  const Eigen::Vector3d axis{std::sin(a) * std::sin(c), std::sin(a) * std::cos(c), std::cos(a)};
  expect_pose_near(forward_ac(p, j),
                   {17.313564858329276, 15.688738488496183, 25.879195107485668 - 7}, axis, 1e-12);
  p.conventional_directions = true;
  expect_pose_near(forward_ac(p, j), {2.5313184775830337, 20.01189117569151, 33.64376646056129 - 7},
                   {std::sin(a) * std::sin(c), -std::sin(a) * std::cos(c), std::cos(a)}, 1e-12);
}

TEST(KinematicsAc, InverseOfHandPose) {
  const ToolPose pose{{100, 0, 0}, {1, 0, 0}};
  const AcIkResult r = inverse_ac({}, pose, {0, 0, 0, 80, 80});
  EXPECT_EQ(r.status, AcIkStatus::kOk);
  EXPECT_LE(max_joint_error(r.joints, {0, 0, 100, 90, 90}), 1e-12);
  // The other solution, when the hint is on that side.
  const AcIkResult other = inverse_ac({}, pose, {0, 0, 0, -80, -80});
  EXPECT_EQ(other.status, AcIkStatus::kOk);
  EXPECT_LE(max_joint_error(other.joints, {0, 0, 100, -90, -90}), 1e-12);
}

// --- randomised round trips -----------------------------------------------

AcTrtParams random_params(std::mt19937_64& rng, bool conventional) {
  std::uniform_real_distribution<double> offset(-300.0, 300.0), tool(0.0, 250.0);
  AcTrtParams p;
  p.x_rot_point_mm = offset(rng);
  p.y_rot_point_mm = offset(rng);
  p.z_rot_point_mm = offset(rng);
  p.y_offset_mm = offset(rng);
  p.z_offset_mm = offset(rng);
  p.tool_length_mm = tool(rng);
  p.conventional_directions = conventional;
  return p;
}

AcJoints random_joints(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> lin(-600.0, 600.0), a(-130.0, 130.0), c(-1000.0, 1000.0);
  return {lin(rng), lin(rng), lin(rng), a(rng), c(rng)};
}

class KinematicsAcRoundTrip : public ::testing::TestWithParam<bool> {};

TEST_P(KinematicsAcRoundTrip, InverseOfForwardReturnsTheJointsNearTheHint) {
  std::mt19937_64 rng(20261121);
  std::uniform_real_distribution<double> jitter(-10.0, 10.0);
  for (int trial = 0; trial < 5000; ++trial) {
    const AcTrtParams p = random_params(rng, GetParam());
    const AcJoints j = random_joints(rng);
    const ToolPose pose = forward_ac(p, j);
    ASSERT_NEAR(pose.axis.norm(), 1.0, 1e-15);
    AcJoints hint = j;
    hint.a_deg += jitter(rng);
    hint.c_deg += jitter(rng);
    const AcIkResult r = inverse_ac(p, pose, hint);
    ASSERT_EQ(r.status, AcIkStatus::kOk) << "trial " << trial;
    ASSERT_LE(max_joint_error(r.joints, j), kTol) << "trial " << trial << " A " << j.a_deg;
  }
}

TEST_P(KinematicsAcRoundTrip, ForwardOfInverseIsIdentityForAnyHint) {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), pos(-500.0, 500.0);
  for (int trial = 0; trial < 5000; ++trial) {
    const AcTrtParams p = random_params(rng, GetParam());
    ToolPose pose;
    pose.tcp_mm = {pos(rng), pos(rng), pos(rng)};
    pose.axis = {unit(rng), unit(rng), unit(rng)};
    if (pose.axis.norm() < 1e-3) continue;
    pose.axis.normalize();
    const AcIkResult r = inverse_ac(p, pose, random_joints(rng));
    ASSERT_NE(r.status, AcIkStatus::kInvalidInput);
    const ToolPose back = forward_ac(p, r.joints);
    ASSERT_LE((back.tcp_mm - pose.tcp_mm).cwiseAbs().maxCoeff(), kTol) << "trial " << trial;
    ASSERT_LE((back.axis - pose.axis).cwiseAbs().maxCoeff(), kTol) << "trial " << trial;
  }
}

TEST_P(KinematicsAcRoundTrip, RoundTripNearTheSingularity) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> log_tilt(-6.0, 0.0), sign(-1.0, 1.0);
  for (int trial = 0; trial < 5000; ++trial) {
    const AcTrtParams p = random_params(rng, GetParam());
    AcJoints j = random_joints(rng);
    j.a_deg = std::copysign(std::pow(10.0, log_tilt(rng)), sign(rng));  // 1e-6 .. 1 deg
    const ToolPose pose = forward_ac(p, j);
    const AcIkResult r = inverse_ac(p, pose, j);
    ASSERT_EQ(r.status, AcIkStatus::kOk) << "trial " << trial;
    ASSERT_LE(max_joint_error(r.joints, j), kTol) << "trial " << trial << " A " << j.a_deg;
    const ToolPose back = forward_ac(p, inverse_ac(p, pose, random_joints(rng)).joints);
    ASSERT_LE((back.tcp_mm - pose.tcp_mm).cwiseAbs().maxCoeff(), kTol) << "trial " << trial;
    ASSERT_LE((back.axis - pose.axis).cwiseAbs().maxCoeff(), kTol) << "trial " << trial;
  }
}

INSTANTIATE_TEST_SUITE_P(Directions, KinematicsAcRoundTrip, ::testing::Bool(),
                         [](const auto& param_info) {
                           return param_info.param ? "conventional" : "linuxcnc";
                         });

// --- singularity ------------------------------------------------------------

TEST(KinematicsAc, VerticalToolKeepsTheHintC) {
  AcTrtParams p;
  p.x_rot_point_mm = 30;
  p.y_offset_mm = 15;
  p.z_offset_mm = -80;
  p.tool_length_mm = 60;
  for (const double hint_c : {0.0, 123.4, -3599.5}) {
    const ToolPose pose{{5, -7, 12}, {0, 0, 1}};
    const AcIkResult r = inverse_ac(p, pose, {0, 0, 0, 3, hint_c});
    EXPECT_EQ(r.status, AcIkStatus::kSingular);
    EXPECT_EQ(r.joints.c_deg, hint_c);
    EXPECT_EQ(r.joints.a_deg, 0.0);
    expect_pose_near(forward_ac(p, r.joints), pose.tcp_mm, pose.axis, kTol);
  }
}

TEST(KinematicsAc, AntiParallelToolIsTheSameSingularity) {
  const AcTrtParams p;
  const ToolPose pose{{4, 5, 6}, {0, 0, -1}};
  const AcIkResult r = inverse_ac(p, pose, {0, 0, 0, 170, 25});
  EXPECT_EQ(r.status, AcIkStatus::kSingular);
  EXPECT_EQ(r.joints.c_deg, 25.0);
  EXPECT_NEAR(std::abs(r.joints.a_deg), 180.0, 1e-12);
  expect_pose_near(forward_ac(p, r.joints), pose.tcp_mm, pose.axis, kTol);
}

TEST(KinematicsAc, TiltInsideTheSingularBandDoesNotSpinC) {
  AcTrtParams p;
  p.singular_tilt_deg = 1e-6;
  // Tilted 1e-7 deg in the C = 90 plane, but the hint sits at C = 10.
  const double t = 1e-7 * M_PI / 180;
  const ToolPose pose{{1, 2, 3}, {std::sin(t), 0, std::cos(t)}};
  const AcIkResult r = inverse_ac(p, pose, {0, 0, 0, 0, 10});
  EXPECT_EQ(r.status, AcIkStatus::kSingular);
  EXPECT_EQ(r.joints.c_deg, 10.0);
  const ToolPose back = forward_ac(p, r.joints);
  EXPECT_LE((back.tcp_mm - pose.tcp_mm).norm(), kTol);
  EXPECT_LE((back.axis - pose.axis).norm(), std::sin(1e-6 * M_PI / 180));
  // Outside the band the same hint gives the exact solution at C = 90.
  p.singular_tilt_deg = 1e-8;
  const AcIkResult exact = inverse_ac(p, pose, {0, 0, 0, 0, 10});
  EXPECT_EQ(exact.status, AcIkStatus::kOk);
  EXPECT_NEAR(exact.joints.c_deg, 90.0, 1e-9);
}

// The singular band is the tilt whose sine lies below sin(singular_tilt_deg)
// (the header's rule, computed here as written), whatever the band's width:
// axes on either side of its edge, and, for wide bands, tilts between sin(x)
// and x (radians), where a cheaper test of the tilt against x alone would
// differ.
TEST(KinematicsAc, TheSingularBandEndsWhereTheRuleSays) {
  for (const double band_deg : {1e-8, 1e-6, 1e-3, 0.5, 10.0, 30.0, 60.0, 80.0}) {
    AcTrtParams p;
    p.singular_tilt_deg = band_deg;
    const double edge = std::sin(band_deg * M_PI / 180);
    int singular = 0, regular = 0;
    for (const double rel : {-1e-9, -1e-12, 0.0, 1e-12, 1e-9, 1e-3, 0.2}) {
      for (const double away_deg : {0.0, 20.0, 40.0, 100.0}) {
        // A tilt angle near the edge, and for wide bands also between the
        // edge's sine and its angle in radians.
        const double t = std::asin(std::min(1.0, edge * (1 + rel))) + away_deg * M_PI / 180 / 1000;
        const double c = 0.7;  // the tilt's plane
        const ToolPose pose{{1, 2, 3},
                            {std::sin(t) * std::sin(c), std::sin(t) * std::cos(c), std::cos(t)}};
        const Eigen::Vector3d n = pose.axis / pose.axis.norm();
        const bool expect_singular = std::hypot(n.x(), n.y()) < edge;
        const AcIkResult r = inverse_ac(p, pose, {0, 0, 0, 0, 10});
        EXPECT_EQ(r.status == AcIkStatus::kSingular, expect_singular)
            << "band " << band_deg << " deg, tilt " << t * 180 / M_PI << " deg";
        (expect_singular ? singular : regular)++;
      }
    }
    EXPECT_GT(singular, 0) << band_deg;
    EXPECT_GT(regular, 0) << band_deg;
  }
}

TEST(KinematicsAc, InverseIsContinuousAlongAPathThroughAZero) {
  AcTrtParams p;
  p.y_offset_mm = 20;
  p.z_offset_mm = -150;
  p.tool_length_mm = 90;
  const double plane_c = 30 * M_PI / 180;
  const int steps = 4000;  // step 0.01 deg; step 2000 is exactly vertical
  AcJoints prev{0, 0, 0, 20, 30};
  bool crossed_singular = false;
  for (int i = 0; i <= steps; ++i) {
    const double tilt_deg = 20.0 - 40.0 * i / steps;
    const double t = tilt_deg * M_PI / 180;
    const ToolPose pose{
        {10.0 + 0.01 * i, -5.0, 40.0},
        {std::sin(t) * std::sin(plane_c), std::sin(t) * std::cos(plane_c), std::cos(t)}};
    const AcIkResult r = inverse_ac(p, pose, prev);
    ASSERT_TRUE(r.status == AcIkStatus::kOk || r.status == AcIkStatus::kSingular) << i;
    crossed_singular |= r.status == AcIkStatus::kSingular;
    ASSERT_NEAR(r.joints.a_deg, tilt_deg, 1e-9) << i;
    ASSERT_NEAR(r.joints.c_deg, 30.0, 1e-9) << i;
    if (i > 0) {
      ASSERT_LE(std::abs(r.joints.y_mm - prev.y_mm), 0.1) << i;
    }
    prev = r.joints;
  }
  EXPECT_TRUE(crossed_singular);
}

TEST(KinematicsAc, CUnwindsAcrossTurns) {
  const AcTrtParams p;
  AcJoints prev{0, 0, 0, 30, 0};
  for (int i = 1; i <= 3000; ++i) {
    const double c_deg = 0.5 * i;  // four turns and more
    const AcJoints target{0, 0, 100, 30, c_deg};
    const AcIkResult r = inverse_ac(p, forward_ac(p, target), prev);
    ASSERT_EQ(r.status, AcIkStatus::kOk);
    ASSERT_NEAR(r.joints.c_deg, c_deg, 1e-9) << i;
    prev = r.joints;
  }
}

TEST(KinematicsAc, ATravelSelectsTheReachableSolution) {
  AcTrtParams p;
  p.a_min_deg = -30;
  p.a_max_deg = 110;
  const ToolPose pose = forward_ac(p, {0, 0, 100, 60, 10});
  // The hint favours the (-60, 190) solution, which is outside the travel.
  const AcIkResult r = inverse_ac(p, pose, {0, 0, 100, -50, 180});
  EXPECT_EQ(r.status, AcIkStatus::kOk);
  EXPECT_NEAR(r.joints.a_deg, 60.0, 1e-9);
  EXPECT_NEAR(r.joints.c_deg, 10.0, 1e-9);

  const ToolPose unreachable = forward_ac(AcTrtParams{}, {0, 0, 100, 150, 0});
  EXPECT_EQ(inverse_ac(p, unreachable, {}).status, AcIkStatus::kOutOfLimits);
}

TEST(KinematicsAc, InvalidInputReturnsTheHint) {
  const AcJoints hint{1, 2, 3, 4, 5};
  const double nan = std::nan("");
  const ToolPose bad_tcp{{nan, 0, 0}, {0, 0, 1}};
  const ToolPose zero_axis{{0, 0, 0}, {0, 0, 0}};
  const ToolPose inf_axis{{0, 0, 0}, {0, HUGE_VAL, 1}};
  for (const ToolPose& pose : {bad_tcp, zero_axis, inf_axis}) {
    const AcIkResult r = inverse_ac({}, pose, hint);
    EXPECT_EQ(r.status, AcIkStatus::kInvalidInput);
    EXPECT_EQ(max_joint_error(r.joints, hint), 0.0);
  }
  EXPECT_EQ(inverse_ac({}, ToolPose{}, {0, 0, 0, nan, 0}).status, AcIkStatus::kInvalidInput);
}

TEST(KinematicsAc, AxisIsNormalised) {
  const AcTrtParams p;
  const ToolPose pose = forward_ac(p, {1, 2, 3, 40, 70});
  ToolPose scaled = pose;
  scaled.axis *= 3.0;
  const AcJoints hint{0, 0, 0, 40, 70};
  EXPECT_LE(max_joint_error(inverse_ac(p, scaled, hint).joints, inverse_ac(p, pose, hint).joints),
            1e-12);
}

}  // namespace
}  // namespace truecut::rt
