// rotary_location (ISO 230-7): each location error alone gives its
// signature in the axis angle — an offset of an axis line a once-per-rev
// error of its size in the offset's phase, a tilt a once-per-rev error
// growing with the distance along the axis, a zero offset a constant
// angular shift.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include <Eigen/Geometry>

#include "machine_fixtures.hpp"
#include "truecut/rt/core/kinematics_ac.hpp"
#include "truecut/sim/true_tool_pose.hpp"

using namespace truecut::sim;
using namespace truecut::sim::test;
using truecut::rt::AcIkStatus;
using truecut::rt::AcJoints;
using truecut::rt::inverse_ac;
using truecut::rt::ToolPose;

namespace {

constexpr double kPi = std::numbers::pi;
constexpr int kSamples = 360;
// Exact relations, up to the rounding of coordinates of a few hundred mm.
constexpr double kExact = 1e-11;

// Fourier coefficients of a signal sampled once per degree over a full turn.
struct Harmonics {
  double mean = 0.0;
  double cos1 = 0.0, sin1 = 0.0;  // first harmonic
  double amp2 = 0.0;              // amplitude of the second
};

Harmonics harmonics(const std::vector<double>& s) {
  Harmonics h;
  double c2 = 0.0, s2 = 0.0;
  const double n = double(s.size());
  for (size_t i = 0; i < s.size(); ++i) {
    const double th = 2 * kPi * double(i) / n;
    h.mean += s[i] / n;
    h.cos1 += 2 * s[i] * std::cos(th) / n;
    h.sin1 += 2 * s[i] * std::sin(th) / n;
    c2 += 2 * s[i] * std::cos(2 * th) / n;
    s2 += 2 * s[i] * std::sin(2 * th) / n;
  }
  h.amp2 = std::hypot(c2, s2);
  return h;
}

// The joints that put the nominal TCP on `point` (workpiece frame) with the
// given tool axis; `hint` picks C where the axis is vertical.
AcJoints joints_for(const MachineParams& m, const Eigen::Vector3d& point,
                    const Eigen::Vector3d& axis, const AcJoints& hint) {
  const auto r = inverse_ac(nominal_ac_params(m), ToolPose{point, axis}, hint);
  EXPECT_TRUE(r.status == AcIkStatus::kOk || r.status == AcIkStatus::kSingular);
  return r.joints;
}

// Where the tool really is when the nominal kinematics aims it at `point`.
Eigen::Vector3d true_tcp(const MachineParams& m, const AcJoints& j) {
  return true_tool_pose(true_kinematics(m), {j.x_mm, j.y_mm, j.z_mm}, j.a_deg, j.c_deg).tcp_mm;
}

struct Sweep {
  std::vector<double> ex, ey, ez;
};

// A point fixed on the table, visited with A = 0 and the C table at
// 0, 1, ..., 359 degrees: the true TCP minus the point.
Sweep sweep_c(const MachineParams& m, const Eigen::Vector3d& point) {
  Sweep s;
  for (int i = 0; i < kSamples; ++i) {
    const AcJoints j = joints_for(m, point, Eigen::Vector3d::UnitZ(), {0, 0, 0, 0, double(i)});
    EXPECT_EQ(double(i), j.c_deg);
    EXPECT_EQ(0.0, j.a_deg);
    const Eigen::Vector3d e = true_tcp(m, j) - point;
    s.ex.push_back(e.x());
    s.ey.push_back(e.y());
    s.ez.push_back(e.z());
  }
  return s;
}

// The same with C = 0 and the trunnion at A = 0, 1, ..., 359 degrees (the
// pure kinematics has no travel limits). The joints come from the nominal
// chain at C = 0, t = P_A + R_x(σA) · (point − P_A), and are checked
// against rt::forward_ac.
Sweep sweep_a(const MachineParams& m, const Eigen::Vector3d& point) {
  Sweep s;
  const auto nominal = nominal_ac_params(m);
  const Eigen::Vector3d pa(nominal.x_rot_point_mm, nominal.y_rot_point_mm + nominal.y_offset_mm,
                           nominal.z_rot_point_mm + nominal.z_offset_mm);
  const double sigma = nominal.conventional_directions ? -1.0 : 1.0;
  for (int i = 0; i < kSamples; ++i) {
    const double alpha = sigma * i * kPi / 180.0;
    const Eigen::Vector3d t =
        pa + Eigen::AngleAxisd(alpha, Eigen::Vector3d::UnitX()) * (point - pa);
    const AcJoints j{t.x(), t.y(), t.z() + nominal.tool_length_mm, double(i), 0.0};
    EXPECT_LT((truecut::rt::forward_ac(nominal, j).tcp_mm - point).norm(), 1e-11);
    const Eigen::Vector3d e = true_tcp(m, j) - point;
    s.ex.push_back(e.x());
    s.ey.push_back(e.y());
    s.ez.push_back(e.z());
  }
  return s;
}

MachineParams with_location(const RotaryLocationA& a, const RotaryLocationC& c,
                            bool conventional = false) {
  MachineParams m = trunnion_params(conventional);
  m.effects.rotary_location = {true, {a, c}};
  return m;
}

const Eigen::Vector3d kC0(120.0, -40.0, -250.0);  // C pivot of trunnion_params()
const Eigen::Vector3d kA0(120.0, -10.0, -190.0);  // A pivot

}  // namespace

TEST(RotaryLocation, OffsetOfTheCAxisLineIsAOncePerRevErrorOfItsSize) {
  RotaryLocationC c;
  c.e_x0c_um = 12.0;
  c.e_y0c_um = -5.0;
  const MachineParams m = with_location({}, c);
  const double dx = 0.012, dy = -0.005;
  // Any point, any height: an offset of a vertical axis does not care.
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(kC0 + Eigen::Vector3d(60, 25, 30)),
                                   Eigen::Vector3d(kC0 + Eigen::Vector3d(-10, 80, 150))}) {
    const Sweep s = sweep_c(m, p);
    // e = (I − R_z(−C)) · δ: zero at C = 0, 2|δ| at C = 180°.
    const Harmonics hx = harmonics(s.ex), hy = harmonics(s.ey), hz = harmonics(s.ez);
    EXPECT_NEAR(dx, hx.mean, kExact);
    EXPECT_NEAR(-dx, hx.cos1, kExact);
    EXPECT_NEAR(-dy, hx.sin1, kExact);
    EXPECT_NEAR(dy, hy.mean, kExact);
    EXPECT_NEAR(-dy, hy.cos1, kExact);
    EXPECT_NEAR(dx, hy.sin1, kExact);
    EXPECT_NEAR(std::hypot(dx, dy), std::hypot(hx.cos1, hx.sin1), kExact) << "first harmonic";
    EXPECT_LT(hx.amp2 + hy.amp2, kExact) << "nothing at 2 per rev";
    EXPECT_LT(std::abs(hz.mean) + std::abs(hz.cos1) + std::abs(hz.sin1), kExact);
    EXPECT_NEAR(0.0, std::hypot(s.ex[0], s.ey[0]), kExact);
    EXPECT_NEAR(2 * std::hypot(dx, dy), std::hypot(s.ex[180], s.ey[180]), kExact);
  }
}

TEST(RotaryLocation, TiltOfTheCAxisLineGrowsWithHeight) {
  RotaryLocationC c;
  c.e_a0c_urad = 40.0;
  c.e_b0c_urad = -25.0;
  const MachineParams m = with_location({}, c);
  double amplitude[2];
  for (int k = 0; k < 2; ++k) {
    const double h = 100.0 * (k + 1);
    // A point on the nominal C axis, h above the reference height: the
    // tilted axis passes h·(E_B0C, −E_A0C) beside it.
    const Sweep s = sweep_c(m, kC0 + Eigen::Vector3d(0, 0, h));
    const double dx = h * -25e-6, dy = h * -40e-6;
    const Harmonics hx = harmonics(s.ex), hy = harmonics(s.ey);
    EXPECT_NEAR(-dx, hx.cos1, 1e-7) << "h " << h;
    EXPECT_NEAR(-dy, hx.sin1, 1e-7);
    EXPECT_NEAR(dx, hy.sin1, 1e-7);
    EXPECT_NEAR(-dy, hy.cos1, 1e-7);
    EXPECT_LT(hx.amp2 + hy.amp2, 1e-7);
    amplitude[k] = std::hypot(hx.cos1, hx.sin1);
    EXPECT_NEAR(h * std::hypot(40e-6, 25e-6), amplitude[k], 1e-7);
  }
  EXPECT_NEAR(2.0, amplitude[1] / amplitude[0], 1e-4) << "linear in height";
  // At the reference height there is nothing.
  const Sweep s0 = sweep_c(m, kC0);
  for (int i = 0; i < kSamples; ++i)
    ASSERT_LT(std::hypot(s0.ex[i], s0.ey[i]), kExact);
}

TEST(RotaryLocation, TiltOfTheCAxisLineWobblesTheTableTop) {
  RotaryLocationC c;
  c.e_a0c_urad = 30.0;
  const MachineParams m = with_location({}, c);
  // A point r off the axis at the reference height rises and falls once per
  // rev by r·tilt (the table top is a swash plate).
  const double r = 150.0;
  const Sweep s = sweep_c(m, kC0 + Eigen::Vector3d(r, 0, 0));
  const Harmonics hz = harmonics(s.ez);
  EXPECT_NEAR(r * 30e-6, std::hypot(hz.cos1, hz.sin1), 1e-7);
  EXPECT_LT(hz.amp2, 1e-7);
}

TEST(RotaryLocation, ZeroOffsetOfCIsAConstantAngularShift) {
  for (bool conventional : {false, true}) {
    RotaryLocationC c;
    c.e_c0c_urad = 100.0;
    const MachineParams m = with_location({}, c, conventional);
    const double sigma = conventional ? -1.0 : 1.0;
    const Eigen::Vector3d p = kC0 + Eigen::Vector3d(70, -30, 20);
    for (int i = 0; i < kSamples; i += 7) {
      const AcJoints j = joints_for(m, p, Eigen::Vector3d::UnitZ(), {0, 0, 0, 0, double(i)});
      const Eigen::Vector3d got = true_tcp(m, j) - kC0, want = p - kC0;
      const double shift = std::atan2(got.y(), got.x()) - std::atan2(want.y(), want.x());
      // The table turned E_C0C further than read: the tool lands behind.
      EXPECT_NEAR(-sigma * 100e-6, shift, kExact) << "C " << i;
      EXPECT_NEAR(want.head<2>().norm(), got.head<2>().norm(), kExact);
      EXPECT_NEAR(want.z(), got.z(), kExact);
    }
  }
}

TEST(RotaryLocation, OffsetOfTheAAxisLineIsAOncePerRevErrorInA) {
  RotaryLocationA a;
  a.e_y0a_um = -8.0;
  a.e_z0a_um = 15.0;
  const MachineParams m = with_location(a, {});
  const Sweep s = sweep_a(m, kC0 + Eigen::Vector3d(40, 20, 35));
  // e = (I − R_x(−A)) · δ with δ = (0, E_Y0A, E_Z0A).
  const double dy = -0.008, dz = 0.015;
  const Harmonics hx = harmonics(s.ex), hy = harmonics(s.ey), hz = harmonics(s.ez);
  EXPECT_NEAR(dy, hy.mean, kExact);
  EXPECT_NEAR(-dy, hy.cos1, kExact);
  EXPECT_NEAR(-dz, hy.sin1, kExact);
  EXPECT_NEAR(dz, hz.mean, kExact);
  EXPECT_NEAR(-dz, hz.cos1, kExact);
  EXPECT_NEAR(dy, hz.sin1, kExact);
  EXPECT_LT(hy.amp2 + hz.amp2, kExact);
  EXPECT_LT(std::abs(hx.mean) + std::hypot(hx.cos1, hx.sin1), kExact) << "nothing along X";
}

TEST(RotaryLocation, TiltOfTheAAxisLineGrowsAlongX) {
  RotaryLocationA a;
  a.e_b0a_urad = 20.0;
  a.e_c0a_urad = 35.0;
  const MachineParams m = with_location(a, {});
  double amplitude[2];
  for (int k = 0; k < 2; ++k) {
    const double d = 80.0 * (k + 1);
    // On the nominal A axis, d along X from the pivot: the tilted line
    // passes d·(E_C0A, −E_B0A) beside it in (Y, Z).
    const Sweep s = sweep_a(m, kA0 + Eigen::Vector3d(d, 0, 0));
    const double dy = d * 35e-6, dz = d * -20e-6;
    const Harmonics hy = harmonics(s.ey), hz = harmonics(s.ez);
    EXPECT_NEAR(-dy, hy.cos1, 1e-7);
    EXPECT_NEAR(-dz, hy.sin1, 1e-7);
    EXPECT_NEAR(-dz, hz.cos1, 1e-7);
    EXPECT_NEAR(dy, hz.sin1, 1e-7);
    amplitude[k] = std::hypot(hy.cos1, hy.sin1);
  }
  EXPECT_NEAR(2.0, amplitude[1] / amplitude[0], 1e-4);
}

TEST(RotaryLocation, ZeroOffsetOfAIsAConstantAngularShift) {
  for (bool conventional : {false, true}) {
    RotaryLocationA a;
    a.e_a0a_urad = -60.0;
    const MachineParams m = with_location(a, {}, conventional);
    const double sigma = conventional ? -1.0 : 1.0;
    const Eigen::Vector3d p = kA0 + Eigen::Vector3d(15, 45, 25);
    const Sweep s = sweep_a(m, p);
    for (int i = 0; i < kSamples; i += 11) {
      const Eigen::Vector3d want = p - kA0;
      const Eigen::Vector3d got = want + Eigen::Vector3d(s.ex[i], s.ey[i], s.ez[i]);
      const double shift = std::atan2(got.z(), got.y()) - std::atan2(want.z(), want.y());
      EXPECT_NEAR(-sigma * -60e-6, shift, kExact) << "A " << i;
      EXPECT_NEAR(0.0, s.ex[i], kExact);
    }
  }
}

TEST(RotaryLocation, CErrorsLiveInTheCradle) {
  // The C axis line's errors are carried by the trunnion: at A = 90° the
  // error in the workpiece frame is the one at A = 0.
  RotaryLocationC c;
  c.e_x0c_um = 10.0;
  const MachineParams m = with_location({}, c);
  const MachineParams ideal = trunnion_params();
  const AcJoints j{150.0, 20.0, -100.0, 90.0, 180.0};
  const Eigen::Vector3d err = true_tcp(m, j) - true_tcp(ideal, j);
  // (I − R_z(−180°)) · (0.01, 0, 0) = (0.02, 0, 0) in the workpiece frame.
  EXPECT_NEAR(0.02, err.x(), kExact);
  EXPECT_NEAR(0.0, err.y(), kExact);
  EXPECT_NEAR(0.0, err.z(), kExact);
}

TEST(RotaryLocation, ToolAxisTiltsWithTheAxisLinesOnly) {
  // Offsets move the TCP, not the tool axis; a tilt of C tilts it by up to
  // twice the tilt at C = 180°.
  RotaryLocationC offset;
  offset.e_x0c_um = 50.0;
  RotaryLocationC tilt;
  tilt.e_b0c_urad = 50.0;
  const AcJoints j{0.0, 0.0, 0.0, 0.0, 180.0};
  const auto axis = [&](const RotaryLocationC& c) {
    return true_tool_pose(true_kinematics(with_location({}, c)), {0, 0, 0}, j.a_deg, j.c_deg).axis;
  };
  EXPECT_LT((axis(offset) - Eigen::Vector3d::UnitZ()).norm(), 1e-15);
  EXPECT_NEAR(100e-6, (axis(tilt) - Eigen::Vector3d::UnitZ()).norm(), kExact);
}
