// The tool-orientation correction (issue 19, point 6) on the real-time side:
// a field's rotation channel (CorrectionField, the .tcf file), its shaping
// in the servo cycle (comp::step: max-tilt and its rate, acceleration and
// jerk), and its application: the tool axis turned in tcp mode, A and C
// turned through rotary_correction() in joint mode.
//
// The oracle for the joint mode is the forward kinematics alone: whatever
// joints the component outputs, forward_ac() of them must put the TCP where
// the translation says and turn the tool axis by the rotation the field
// holds (rotate_axis() is checked against Eigen's AngleAxis first).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "test_paths.hpp"
#include "test_truecut_comp_support.hpp"
#include "truecut/rt/comp.hpp"
#include "truecut/rt/executor.hpp"
#include "truecut/rt/field_file.hpp"
#include "truecut/rt/hal_file.hpp"

using namespace truecut;
using namespace truecut::test;
using namespace truecut::test::comp;
using rt::comp::Vec3;

namespace {

constexpr double kDegPerRad = 180.0 / M_PI;

FieldSpec rotating_spec(double rotation_scale = 1.0) {
  FieldSpec s;
  s.origin_mm = {-40.0, -40.0, -30.0};
  s.dims = {17, 17, 13};
  s.rotation_scale = rotation_scale;
  return s;
}

// The axis a field's rotation asks for, from its definition (k + r x k,
// normalised), written out here independently of the component.
Vec3 wanted_axis(const Vec3& k, const Vec3& r) {
  const Vec3 t(k.x() + r.y() * k.z() - r.z() * k.y(), k.y() + r.z() * k.x() - r.x() * k.z(),
               k.z() + r.x() * k.y() - r.y() * k.x());
  return t / std::sqrt(t.x() * t.x() + t.y() * t.y() + t.z() * t.z());
}

}  // namespace

TEST(ToolRotationField, NodesGiveTheirRotationAndTheWeightScalesIt) {
  FieldSpec spec = rotating_spec();
  spec.fading_border = true;
  const rt::CorrectionField field = make_field(spec);
  ASSERT_TRUE(field.has_rotation());
  const rt::FieldGrid& g = field.grid();
  for (const auto interpolation :
       {rt::FieldInterpolation::kTricubicBspline, rt::FieldInterpolation::kTrilinear}) {
    for (int32_t k = 0; k < g.dims[2]; k += 3)
      for (int32_t j = 0; j < g.dims[1]; j += 4)
        for (int32_t i = 0; i < g.dims[0]; i += 5) {
          const Eigen::Vector3d p = g.node_position_mm(i, j, k);
          const rt::FieldSample s = interpolation == rt::FieldInterpolation::kTrilinear
                                        ? field.evaluate_trilinear(1, p)
                                        : field.evaluate_tricubic(1, p);
          ASSERT_EQ(rt::FieldStatus::kOk, s.status);
          const double w = field.nodes(1)[static_cast<std::size_t>(g.index(i, j, k))].weight;
          EXPECT_EQ(w, s.weight);
          // A valid node gives its own rotation; an invalid one none.
          const Vec3 want = w * synthetic_rotation(1, 1.0, p);
          EXPECT_NEAR(0.0, (s.rotation_rad - want).norm(), 1e-15) << p.transpose();
        }
  }
  // Between nodes: weighted like the vector.
  const Eigen::Vector3d mid(1.3, -2.7, 4.1);
  const rt::FieldSample s = field.evaluate(2, mid);
  ASSERT_EQ(rt::FieldStatus::kOk, s.status);
  EXPECT_GT(s.rotation_rad.norm(), 1e-4);
  EXPECT_NEAR(0.0, (s.rotation_rad - synthetic_rotation(2, 1.0, mid)).norm(), 2e-5)
      << "smooth between nodes 5 mm apart";
}

TEST(ToolRotationField, AFieldWithoutRotationGivesExactlyNone) {
  const rt::CorrectionField field = make_field(rotating_spec(0.0));
  EXPECT_FALSE(field.has_rotation());
  EXPECT_TRUE(field.rotations(1).empty());
  const rt::FieldSample s = field.evaluate(1, {3.0, 4.0, 5.0});
  ASSERT_EQ(rt::FieldStatus::kOk, s.status);
  EXPECT_EQ(Vec3::Zero(), s.rotation_rad);
}

TEST(ToolRotationField, LayersMustAllHaveARotationOrNone) {
  rt::CorrectionField full = make_field(rotating_spec());
  rt::FieldGrid g = full.grid();
  std::vector<rt::FieldLayer> layers;
  for (int32_t t : full.tools()) {
    rt::FieldLayer l{t, std::vector<rt::FieldNode>(full.nodes(t).begin(), full.nodes(t).end())};
    if (t == 1) l.rotation_rad.assign(full.rotations(t).begin(), full.rotations(t).end());
    layers.push_back(std::move(l));
  }
  try {
    rt::CorrectionField mixed(g, layers);
    FAIL() << "a field with a rotation in one layer only was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("tool 2 has no rotation"), std::string::npos) << e.what();
  }
  layers[1].rotation_rad.assign(full.rotations(1).begin(), full.rotations(1).end());
  layers[1].rotation_rad[7].x() = std::nan("");
  try {
    rt::CorrectionField bad(g, layers);
    FAIL() << "a NaN rotation was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("non-finite rotation at node index 7"), std::string::npos)
        << e.what();
  }
}

TEST(ToolRotationField, FileCarriesTheRotationChannelsBitForBit) {
  const rt::CorrectionField field = make_field(rotating_spec());
  const std::string bytes = rt::encode_field_file(field, {"2026-11-28T00:00:00Z", "test"});
  EXPECT_NE(bytes.find("\nchannels: dx dy dz rx ry rz weight\n"), std::string::npos);
  const rt::LoadedField back = rt::decode_field_file(bytes, "rot.tcf");
  ASSERT_TRUE(back.field.has_rotation());
  for (int32_t t : field.tools()) {
    ASSERT_EQ(field.rotations(t).size(), back.field.rotations(t).size());
    for (std::size_t n = 0; n < field.rotations(t).size(); ++n) {
      ASSERT_EQ(field.rotations(t)[n], back.field.rotations(t)[n]) << n;
      ASSERT_EQ(field.nodes(t)[n].weight, back.field.nodes(t)[n].weight) << n;
    }
  }
  // 7 float64 per node.
  const std::size_t payload =
      field.tools().size() * static_cast<std::size_t>(field.grid().node_count()) * 7 * 8;
  EXPECT_NE(bytes.find("payload_bytes: " + std::to_string(payload) + "\n"), std::string::npos);

  // Without rotation the file keeps its four channels.
  const std::string plain =
      rt::encode_field_file(make_field(rotating_spec(0.0)), {"2026-11-28T00:00:00Z", "test"});
  EXPECT_NE(plain.find("\nchannels: dx dy dz weight\n"), std::string::npos);
}

TEST(ToolRotationField, UnknownChannelsAndABadRotationValueAreNamed) {
  const rt::CorrectionField field = make_field(rotating_spec());
  std::string bytes = rt::encode_field_file(field, {"2026-11-28T00:00:00Z", "test"});
  std::string wrong = bytes;
  wrong.replace(wrong.find("rx ry rz"), 8, "rx ry rq");
  try {
    rt::decode_field_file(wrong, "rot.tcf");
    FAIL();
  } catch (const rt::FieldFileError& e) {
    EXPECT_NE(
        std::string(e.what()).find("rot.tcf: channels is 'dx dy dz rx ry rq weight', must be"),
        std::string::npos)
        << e.what();
  }
  // A NaN in ry of node 0 of the first layer: named by channel. (The CRC
  // would catch it too; the value check comes after it, so rewrite the CRC.)
  const std::size_t payload_at = bytes.find("end_header\n") + 11;
  const double nan = std::nan("");
  std::memcpy(&bytes[payload_at + 4 * 8], &nan, 8);
  const std::size_t crc_at = bytes.find("crc64: ");
  rt::Crc64 crc;
  crc.update(std::string_view(bytes).substr(0, crc_at));
  crc.update(std::string_view(bytes).substr(payload_at));
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(crc.value()));
  bytes.replace(crc_at + 7, 16, hex);
  try {
    rt::decode_field_file(bytes, "rot.tcf");
    FAIL();
  } catch (const rt::FieldFileError& e) {
    EXPECT_NE(std::string(e.what()).find("node (i, j, k) = (0, 0, 0), channel ry"),
              std::string::npos)
        << e.what();
  }
}

TEST(ToolRotation, TiltedAxisIsTheFieldsDefinitionAndNearlyTheRotation) {
  const Vec3 k = Vec3(0.3, -0.5, 0.8).normalized();
  for (const Vec3& r : {Vec3(1e-3, 0, 0), Vec3(2e-3, -4e-3, 1e-3), Vec3(0, 0, 2.5e-3)}) {
    EXPECT_NEAR(0.0, (rt::comp::tilted_axis(k, r) - wanted_axis(k, r)).norm(), 1e-15);
    // For milliradians it is the rotation by r to within |r|^2 / 2.
    const Vec3 rotated = Eigen::AngleAxisd(r.norm(), r.normalized()) * k;
    EXPECT_LE((rt::comp::tilted_axis(k, r) - rotated).norm(), 0.5 * r.squaredNorm());
  }
  EXPECT_EQ(k, rt::comp::tilted_axis(k, Vec3::Zero()));
}

// A planted tilt at a tilted table: A and C turn so that the tool axis
// turns by exactly the rotation (its part across the axis), and X Y Z put
// the TCP where the translation says.
TEST(ToolRotation, JointModeTurnsTheToolAxisByThePlantedRotation) {
  rt::AcTrtParams k = joint_test_kinematics();
  rt::comp::JointLimits limits;
  // At A = 4 deg a tilt sideways needs C to turn by tilt / sin A: 1.2 deg.
  limits.max_a_correction_deg = limits.max_c_correction_deg = 10.0;
  for (const bool conventional : {false, true}) {
    k.conventional_directions = conventional;
    for (const double a_deg : {-60.0, -12.0, 4.0, 30.0, 85.0})
      for (const double c_deg : {-170.0, 0.0, 40.0, 135.0}) {
        const rt::AcJoints j{3.0, -7.0, 60.0, a_deg, c_deg};
        const rt::ToolPose pose = rt::forward_ac(k, j);
        for (const Vec3& r : {Vec3(2e-3, 0, 0), Vec3(0, -1.5e-3, 0), Vec3(4e-4, 7e-4, -3e-4)}) {
          const Vec3 t(0.012, -0.004, 0.02);
          const rt::comp::RotaryCorrection rc = rt::comp::rotary_correction(k, j, pose, r, limits);
          EXPECT_FALSE(rc.clipped);
          const rt::AcJoints out = rt::comp::correct_joints(k, j, pose, t, rc);
          const rt::ToolPose got = rt::forward_ac(k, out);
          EXPECT_NEAR(0.0, (got.axis - wanted_axis(pose.axis, r)).norm(), 1e-12)
              << "A " << a_deg << " C " << c_deg << " r " << r.transpose();
          EXPECT_NEAR(0.0, (got.tcp_mm - (pose.tcp_mm + t)).norm(), 1e-9);
          EXPECT_LE(rc.shortfall_rad, 1e-9);
        }
      }
  }
}

// At A = 0 a tilt about the A line is given by A alone; a tilt sideways
// would need C to turn by tilt / sin A: it is left out, reported as the
// shortfall, and C stays put. The turn is continuous as A passes through
// the damped zone.
TEST(ToolRotation, NearTheSingularityASidewaysTiltIsLeftOutNotSpun) {
  rt::AcTrtParams k;
  k.tool_length_mm = 40;
  rt::comp::JointLimits limits;
  // Bounds far above what the sweep below needs (C 1.1 deg at A 3 deg):
  // this is the damping alone.
  limits.max_a_correction_deg = limits.max_c_correction_deg = 10.0;
  const Vec3 about_a(1e-3, 0, 0), sideways(0, 1e-3, 0);
  const rt::AcJoints j0{0, 0, 50, 0, 0};
  const rt::ToolPose p0 = rt::forward_ac(k, j0);
  const rt::comp::RotaryCorrection ra = rt::comp::rotary_correction(k, j0, p0, about_a, limits);
  // The axis becomes (z + r x z) normalised: a tilt of atan(1e-3).
  EXPECT_NEAR(std::atan(1e-3) * kDegPerRad, std::abs(ra.da_deg), 1e-12);
  EXPECT_EQ(0.0, ra.dc_deg);
  EXPECT_LE(ra.shortfall_rad, 1e-9);
  const rt::comp::RotaryCorrection rs = rt::comp::rotary_correction(k, j0, p0, sideways, limits);
  EXPECT_NEAR(0.0, rs.da_deg, 1e-12);
  EXPECT_NEAR(0.0, rs.dc_deg, 1e-12);
  EXPECT_NEAR(1e-3, rs.shortfall_rad, 1e-9);

  // Sweep A through the damped zone (|A| < 2 deg): C's turn never exceeds
  // |dk| / sin(2 deg), changes by little between neighbouring A, and the
  // solution is exact above the zone.
  double prev_dc = 0.0;
  for (int i = 0; i <= 400; ++i) {
    const double a_deg = -4.0 + 0.02 * i;
    const rt::AcJoints j{0, 0, 50, a_deg, 10.0};
    const rt::ToolPose p = rt::forward_ac(k, j);
    const rt::comp::RotaryCorrection rc = rt::comp::rotary_correction(k, j, p, sideways, limits);
    const double dk = sideways.cross(p.axis).norm();
    EXPECT_LE(std::abs(rc.dc_deg) / kDegPerRad, dk / rt::comp::kRotaryDampingStart * (1 + 1e-9))
        << a_deg;
    if (i > 0) {
      EXPECT_LT(std::abs(rc.dc_deg - prev_dc), 0.05) << "C jumps at A " << a_deg;
    }
    prev_dc = rc.dc_deg;
    if (std::abs(a_deg) > 2.05) {
      EXPECT_LE(rc.shortfall_rad, 1e-9) << a_deg;
    }
  }
}

TEST(ToolRotation, RotaryTurnsAreClippedToTheirBoundsAndReported) {
  rt::AcTrtParams k;
  k.tool_length_mm = 40;
  rt::comp::JointLimits limits;
  limits.max_a_correction_deg = 0.05;
  const rt::AcJoints j{0, 0, 50, 20, 0};
  const rt::ToolPose p = rt::forward_ac(k, j);
  const rt::comp::RotaryCorrection rc =
      rt::comp::rotary_correction(k, j, p, Vec3(3e-3, 0, 0), limits);
  EXPECT_TRUE(rc.clipped);
  // (The exact inverse of the axis the clipped turn reaches differs from it
  // at third order: (0.05 deg)^3 / 3 in rad.)
  EXPECT_NEAR(0.05, std::abs(rc.da_deg), 1e-7);
  EXPECT_LE(std::abs(rc.da_deg), 0.05) << "the bound is hard";
  EXPECT_NEAR(3e-3 - 0.05 / kDegPerRad, rc.shortfall_rad, 1e-6);
  limits.max_c_correction_deg = std::nan("");  // C does not move
  const rt::comp::RotaryCorrection rc2 =
      rt::comp::rotary_correction(k, j, p, Vec3(0, 0, 3e-3), limits);
  EXPECT_EQ(0.0, rc2.dc_deg);
  EXPECT_TRUE(rc2.clipped);
}

namespace {

// One truecut_comp `c` stepped by hand (as test_truecut_comp.cpp's Rig).
struct Rig {
  rt::hal::Hal hal{hal_options()};
  std::unique_ptr<rt::hal::Executor> ex;
  explicit Rig(const std::string& args, const std::string& extra = "") {
    rt::hal::load_hal_text(hal,
                           "loadrt threads name1=servo-thread period1=1000000\n"
                           "loadrt truecut_comp names=c " +
                               args + "\naddf c.update servo-thread\n" + extra,
                           "rig.hal");
    ex = std::make_unique<rt::hal::Executor>(hal);
  }
  void set(const std::string& pin, double v) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    hal.set_pin_or_param("c." + pin, buf);
  }
  double get(const std::string& pin) const { return hal.get_pin_or_param("c." + pin).f; }
  Vec3 get3(const std::string& stem) const {
    return {get(stem + "x"), get(stem + "y"), get(stem + "z")};
  }
  void run(int n) {
    for (int i = 0; i < n; ++i)
      ex->step();
  }
};

}  // namespace

TEST(ToolRotationComp, TcpModeTurnsTheAxisOutput) {
  const auto path = write_field(scratch_dir() / "rot.tcf", rotating_spec());
  const rt::CorrectionField field = make_field(rotating_spec());
  Rig r("field=" + path.string(),
        "setp c.fade-time 0\nsetp c.max-rate 1e9\nsetp c.max-accel 0\nsetp c.max-jerk 0\n"
        "setp c.max-tilt-rate 1e9\nsetp c.max-tilt-accel 0\nsetp c.max-tilt-jerk 0\n"
        "setp c.tool 1\n");
  const Vec3 tcp(4.0, -6.0, 3.0), axis = Vec3(0.2, 0.1, 1.0).normalized();
  for (int i = 0; i < 3; ++i) {
    r.set(std::string("tcp-") + "xyz"[i], tcp[i]);
    r.set(std::string("axis-") + "ijk"[i], axis[i]);
  }
  r.run(2);
  EXPECT_EQ(axis, Vec3(r.get("axis-i-out"), r.get("axis-j-out"), r.get("axis-k-out")))
      << "disabled: the axis passes bit for bit";
  EXPECT_EQ(Vec3::Zero(), r.get3("tilt-"));
  r.set("enable", 1.0);
  r.run(2);
  const Vec3 rot = field.evaluate(1, tcp).rotation_rad;
  ASSERT_GT(rot.norm(), 1e-4);
  EXPECT_NEAR(0.0, (r.get3("tilt-") - rot).norm(), 1e-15);
  EXPECT_NEAR(rot.norm(), r.get("tilt-mag"), 1e-15);
  const Vec3 out(r.get("axis-i-out"), r.get("axis-j-out"), r.get("axis-k-out"));
  EXPECT_NEAR(0.0, (out - wanted_axis(axis, rot)).norm(), 1e-15);
}

TEST(ToolRotationComp, JointModeGivesThePlantedTiltThroughAAndC) {
  const auto path = write_field(scratch_dir() / "rot.tcf", rotating_spec());
  const rt::CorrectionField field = make_field(rotating_spec());
  Rig r("field=" + path.string() + " mode=joint",
        std::string(kJointTestKinematicsHal) +
            "setp c.fade-time 0\nsetp c.max-rate 1e9\nsetp c.max-accel 0\nsetp c.max-jerk 0\n"
            "setp c.max-tilt-rate 1e9\nsetp c.max-tilt-accel 0\nsetp c.max-tilt-jerk 0\n"
            "setp c.tool 1\n");
  const rt::AcTrtParams k = joint_test_kinematics();
  const rt::AcJoints j{3.0, -7.0, 60.0, 25.0, 40.0};
  const double v[] = {j.x_mm, j.y_mm, j.z_mm, j.a_deg, j.c_deg};
  for (int i = 0; i < 5; ++i)
    r.set(kJointInputPins[i], v[i]);
  r.set("enable", 1.0);
  r.run(2);
  const rt::ToolPose in = rt::forward_ac(k, j);
  const rt::FieldSample s = field.evaluate(1, in.tcp_mm);
  ASSERT_GT(s.rotation_rad.cross(in.axis).norm(), 1e-4) << "the planted tilt turns the axis";
  const rt::AcJoints out{r.get("joint-x-out"), r.get("joint-y-out"), r.get("joint-z-out"),
                         r.get("joint-a-out"), r.get("joint-c-out")};
  EXPECT_NE(j.a_deg, out.a_deg);
  const rt::ToolPose got = rt::forward_ac(k, out);
  EXPECT_NEAR(0.0, (got.tcp_mm - (in.tcp_mm + s.correction_mm)).norm(), 1e-9);
  EXPECT_NEAR(0.0, (got.axis - wanted_axis(in.axis, s.rotation_rad)).norm(), 1e-12);
  EXPECT_LE(r.get("tilt-shortfall"), 1e-9);

  // A field without rotation leaves A and C bit for bit.
  write_field(path, rotating_spec(0.0));
  r.hal.set_pin_or_param("c.reload", "1");
  r.run(1);
  r.hal.run_services();
  r.run(3);
  EXPECT_EQ(2, r.hal.get_pin_or_param("c.field-generation").s);
  EXPECT_EQ(j.a_deg, r.get("joint-a-out"));
  EXPECT_EQ(j.c_deg, r.get("joint-c-out"));
  EXPECT_EQ(Vec3::Zero(), r.get3("tilt-"));
}

// The rotation obeys its own limits in every transition: fade in with
// fade-time 0 (a step of the wanted tilt), max-tilt lowered, disable.
TEST(ToolRotationComp, TheTiltMovesWithinItsLimitsAndItsBoundIsHard) {
  const FieldSpec spec = rotating_spec(2.0);
  const auto path = write_field(scratch_dir() / "rot.tcf", spec);
  const double rate = 0.01, accel = 2.0, jerk = 500.0, dt = 1e-3;
  Rig r("field=" + path.string(), "setp c.fade-time 0\nsetp c.tool 1\n");
  r.set("max-tilt-rate", rate);
  r.set("max-tilt-accel", accel);
  r.set("max-tilt-jerk", jerk);
  for (int i = 0; i < 3; ++i)
    r.set(std::string("tcp-") + "xyz"[i], Vec3(4.0, -6.0, 3.0)[i]);
  std::vector<Vec3> out{Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
  auto check_cycle = [&](const std::string& phase) {
    const Vec3 y = r.get3("tilt-");
    out.push_back(y);
    const std::size_t n = out.size();
    const Vec3 v = (out[n - 1] - out[n - 2]) / dt, v0 = (out[n - 2] - out[n - 3]) / dt;
    const Vec3 v00 = (out[n - 3] - out[n - 4]) / dt;
    const Vec3 a = (v - v0) / dt, a0 = (v0 - v00) / dt;
    EXPECT_LE(v.norm(), rate * (1 + 1e-6)) << phase;
    EXPECT_LE(a.norm(), accel * (1 + 1e-6)) << phase;
    EXPECT_LE((a - a0).norm() / dt, jerk * (1 + 1e-6)) << phase;
    EXPECT_LE(y.norm(), r.get("max-tilt")) << phase;
  };
  out.push_back(Vec3::Zero());
  r.set("enable", 1.0);
  for (int i = 0; i < 3000; ++i) {
    r.run(1);
    check_cycle("fade in");
  }
  const double full = r.get("tilt-mag");
  ASSERT_GT(full, 3e-3);
  EXPECT_EQ(0, r.hal.get_pin_or_param("c.fault").s);
  // Lowering max-tilt by less than the limits can follow in one cycle (from
  // rest, jerk x dt^3 = 5e-7 rad): ramped down within them.
  r.set("max-tilt", full - 4e-7);
  for (int i = 0; i < 50; ++i) {
    r.run(1);
    check_cycle("bound lowered");
  }
  EXPECT_EQ(0, r.hal.get_pin_or_param("c.fault-latched").s);
  // A bound below what the limits can reach in one cycle: the bound wins,
  // and the step latches bound-step (8).
  r.set("max-tilt", 1e-4);
  r.run(1);
  EXPECT_LE(r.get("tilt-mag"), 1e-4);
  EXPECT_EQ(8, r.hal.get_pin_or_param("c.fault-latched").s);
  // Disable always wins: the tilt reaches zero.
  r.set("enable", 0.0);
  r.run(3000);
  EXPECT_EQ(Vec3::Zero(), r.get3("tilt-"));
  // A negative max-tilt-rate is refused and latched (bad-parameter, 6).
  r.set("reset", 1.0);
  r.run(1);
  EXPECT_EQ(0, r.hal.get_pin_or_param("c.fault-latched").s);
  r.set("max-tilt-rate", -1.0);
  r.run(1);
  EXPECT_EQ(6, r.hal.get_pin_or_param("c.fault").s);
  EXPECT_EQ(6, r.hal.get_pin_or_param("c.fault-latched").s);
}
