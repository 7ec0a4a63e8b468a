// tool_deflection and workpiece_deflection: the cantilever signatures
// (δ = F/k at the tool tip, the tilt's displacement along the tool, δ ∝ h³
// along the part), off by default, JSON errors and round trip, and the
// machine_joints pins in a .hal run.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>

#include "machine_fixtures.hpp"
#include "test_paths.hpp"
#include "truecut/rt/executor.hpp"
#include "truecut/rt/hal_file.hpp"

using namespace truecut::sim;
using namespace truecut::sim::test;
using Eigen::Vector3d;
using nlohmann::json;

namespace {

Vector3d v3(const std::array<double, 3>& a) {
  return {a[0], a[1], a[2]};
}
std::array<double, 3> arr(const Vector3d& v) {
  return {v.x(), v.y(), v.z()};
}

// The trunnion machine at a tilted pose, so that the tool axis is not a
// machine axis in the workpiece frame.
const std::array<double, kJointCount> kTilted = {150.0, 20.0, -90.0, 35.0, 200.0};

struct Step {
  MachineOutputs out;
  MachineState state;
};

Step step_once(const MachineParams& m, const std::array<double, kJointCount>& pos,
               const Vector3d& force_n, const Vector3d& contact_mm) {
  MachineModel model(m);
  Step s;
  MachineInputs in;
  in.pos_cmd = pos;
  in.cut_force_n = arr(force_n);
  in.cut_contact_mm = arr(contact_mm);
  model.step(s.state, in, 1e-3, s.out);
  return s;
}

// The undeflected true pose at `pos` (every deflection off).
MachineOutputs rigid(const MachineParams& m, const std::array<double, kJointCount>& pos) {
  MachineParams r = m;
  r.effects.tool_deflection.enabled = false;
  r.effects.workpiece_deflection.enabled = false;
  return step_once(r, pos, Vector3d::Zero(), Vector3d::Zero()).out;
}

MachineParams with_tool_deflection(double k_n_per_um, std::optional<double> stickout_mm) {
  MachineParams m = trunnion_params();
  m.effects.tool_deflection = {true, {k_n_per_um, stickout_mm}};
  return m;
}

// A unit vector across `axis`.
Vector3d across(const Vector3d& axis) {
  return axis.cross(Vector3d(0.3, -0.5, 0.8)).normalized();
}

}  // namespace

TEST(ToolDeflection, ForceAtTheTipDeflectsTheTipByFOverK) {
  const MachineParams m = with_tool_deflection(2.0, 15.0);  // Ø3 carbide, 15 mm stick-out
  const MachineOutputs r = rigid(m, kTilted);
  const Vector3d axis = v3(r.tool_axis_true), tip = v3(r.tcp_true);
  const Vector3d f = 50.0 * across(axis);
  const MachineOutputs out = step_once(m, kTilted, f, tip).out;
  const Vector3d want = f / 2.0 * 1e-3;  // 25 µm along F
  EXPECT_LT((v3(out.tool_deflection_mm) - want).norm(), 1e-15);
  EXPECT_LT((v3(out.tcp_true) - tip - want).norm(), 1e-12);
  EXPECT_NEAR(0.025, v3(out.tool_deflection_mm).norm(), 1e-15);
  EXPECT_EQ(0.0, v3(out.workpiece_deflection_mm).norm());
  // Twice the force, twice the deflection; the axial part bends nothing.
  const MachineOutputs twice = step_once(m, kTilted, 2.0 * f + 300.0 * axis, tip).out;
  EXPECT_LT((v3(twice.tool_deflection_mm) - 2.0 * want).norm(), 1e-12);
  const MachineOutputs axial = step_once(m, kTilted, -300.0 * axis, tip).out;
  EXPECT_EQ(r.tcp_true, axial.tcp_true);
  EXPECT_EQ(r.tool_axis_true, axial.tool_axis_true);
}

TEST(ToolDeflection, TiltGivesTheCantileverDisplacementAlongTheTool) {
  const double k = 2.0, L = 15.0;
  const MachineParams m = with_tool_deflection(k, L);
  const MachineOutputs r = rigid(m, kTilted);
  const Vector3d axis = v3(r.tool_axis_true), tip = v3(r.tcp_true), dir = across(axis);
  const double f = 50.0, d_tip = f / k * 1e-3;
  const MachineOutputs out = step_once(m, kTilted, f * dir, tip).out;
  const Vector3d axis_d = v3(out.tool_axis_true);
  EXPECT_NEAR(1.0, axis_d.norm(), 1e-15);
  EXPECT_LT(axis_d.dot(dir), 0.0) << "the tip leans out along F, the axis tilts towards -F";
  const double theta = 1.5 * d_tip / L;  // slope at the tip of a tip-loaded cantilever
  EXPECT_NEAR(theta, std::asin(-axis_d.dot(dir)), 1e-15);
  const ToolBend bend = tool_bend(k, L, f * dir, axis, 0.0);
  for (double u : {0.0, 1.0, 2.5, 5.0, 7.5, 10.0, 15.0}) {
    // The deflected straight tool (tip + axis) against the rigid one at height u.
    const Vector3d shift = (v3(out.tcp_true) + u * axis_d) - (tip + u * axis);
    const double line = shift.dot(dir);
    // The axis is turned by θ exactly, so across the tool the line is
    // δ − u·sin θ; the small-angle line δ·(1 − 1.5·u/L) differs by u·θ³/6.
    // (1e-12: the rounding of workpiece coordinates of some 100 mm.)
    EXPECT_NEAR(d_tip - u * std::sin(theta), line, 1e-12) << u;
    EXPECT_NEAR(d_tip * (1.0 - 1.5 * u / L), line, u * theta * theta * theta / 6 + 1e-12) << u;
    // The exact curve lies above the line by δ·(u/L)³/2: 0.4 % of δ at u = L/5.
    const double eta = u / L;
    EXPECT_NEAR(0.5 * eta * eta * eta * d_tip, tool_bend_at(bend, u) - (d_tip - theta * u), 1e-15)
        << u;
  }
  EXPECT_NEAR(0.0, tool_bend_at(bend, L), 1e-18) << "the holder does not move";
  // A wall cut with the side from u = 0 to 5 mm tapers by 1.5·δ·5/L.
  EXPECT_NEAR(0.0125, 1.5 * d_tip * 5.0 / L, 1e-15);
}

TEST(ToolDeflection, LoadAboveTheTipBendsLessAndKeepsTheToolStraightBelowIt) {
  const double k = 0.5, L = 20.0, f = 10.0, u_f = 4.0;
  const Vector3d axis = Vector3d(0.0, 0.6, 0.8), dir = across(axis);
  const ToolBend b = tool_bend(k, L, f * dir, axis, u_f);
  const double c = f / k * 1e-3, s_f = 1.0 - u_f / L;
  EXPECT_NEAR(c * s_f * s_f * (3.0 - s_f) / 2.0, b.tip_mm.norm(), 1e-15);
  EXPECT_LT((b.tip_mm.normalized() - dir).norm(), 1e-15);
  // At the load point: F·a³/(3EI) = (F/k)·(a/L)³.
  EXPECT_NEAR(c * s_f * s_f * s_f, tool_bend_at(b, u_f), 1e-15);
  for (double u : {0.0, 1.0, 3.0, 4.0})
    EXPECT_NEAR(b.tip_mm.norm() - b.slope_rad * u, tool_bend_at(b, u), 1e-15) << "straight";
  for (double u : {6.0, 10.0, 16.0}) {
    const double e = (u - u_f) / L;
    EXPECT_NEAR(0.5 * c * e * e * e, tool_bend_at(b, u) - (b.tip_mm.norm() - b.slope_rad * u),
                1e-15)
        << u;
  }
  // Through the model: the load height is the contact's height along the tool.
  const MachineParams m = with_tool_deflection(k, L);
  const MachineOutputs r = rigid(m, kTilted);
  const Vector3d ax = v3(r.tool_axis_true), d = across(ax);
  const Vector3d contact = v3(r.tcp_true) + u_f * ax + 1.5 * d;  // on the tool's side
  const MachineOutputs out = step_once(m, kTilted, -f * d, contact).out;
  EXPECT_NEAR(c * s_f * s_f * (3.0 - s_f) / 2.0, v3(out.tool_deflection_mm).norm(), 1e-15);
  EXPECT_LT((v3(out.tool_deflection_mm).normalized() + d).norm(), 1e-12);
}

TEST(ToolDeflection, StickoutDefaultsToTheRealToolLength) {
  MachineParams m = with_tool_deflection(1.0, std::nullopt);
  m.effects.tool_length_error = {true, {0.5}};
  EXPECT_EQ(80.5, MachineModel(m).tool_stickout_mm());
  m.effects.tool_deflection.params.stickout_mm = 30.0;
  EXPECT_EQ(30.0, MachineModel(m).tool_stickout_mm());
}

TEST(WorkpieceDeflection, GrowsWithTheCubeOfTheHeightAboveTheClamp) {
  WorkpieceDeflectionParams p;
  p.stiffness_n_per_um = 0.04;  // a 1.6 mm square Ti6Al4V shaft, 17 mm
  p.reference_length_mm = 17.0;
  p.clamp_point_mm = {1.0, 2.0, -3.0};
  p.axis = {0.0, 0.0, 2.0};  // any length
  const Vector3d f(1.0, 0.5, 0.0);
  auto at = [&](double h) { return workpiece_deflection_mm(p, f, Vector3d(0.3, 7.0, -3.0 + h)); };
  EXPECT_LT((at(17.0) - f / 0.04 * 1e-3).norm(), 1e-15) << "F/k_ref at L_ref";
  for (double h : {1.0, 4.25, 8.5, 12.0, 17.0, 20.0}) {
    const double r = h / 17.0;
    EXPECT_LT((at(h) - f / 0.04 * 1e-3 * r * r * r).norm(), 1e-15) << h;
  }
  EXPECT_NEAR(8.0, at(17.0).norm() / at(8.5).norm(), 1e-12);
  EXPECT_EQ(Vector3d::Zero(), at(0.0)) << "at the clamp";
  EXPECT_EQ(Vector3d::Zero(), at(-2.0)) << "below the clamp";
  // Only the force across the cantilever axis bends it.
  EXPECT_EQ(Vector3d::Zero(), workpiece_deflection_mm(p, Vector3d(0, 0, -40), {0, 0, 14}));
  const Vector3d mixed = workpiece_deflection_mm(p, Vector3d(3, 0, 4), {0, 0, 14});
  EXPECT_LT((mixed - Vector3d(3, 0, 0) / 0.04 * 1e-3).norm(), 1e-15);
  // A tilted cantilever.
  p.axis = {1.0, 0.0, 1.0};
  p.clamp_point_mm = {0.0, 0.0, 0.0};
  const Vector3d a = Vector3d(1, 0, 1).normalized();
  const Vector3d d = workpiece_deflection_mm(p, Vector3d(0, 2, 5), 17.0 * a);
  const Vector3d f_across = Vector3d(0, 2, 5) - a * a.dot(Vector3d(0, 2, 5));
  EXPECT_LT((d - f_across / 0.04 * 1e-3).norm(), 1e-15);
}

TEST(WorkpieceDeflection, MovesTheTrueTcpAlongTheForceOnTheTool) {
  MachineParams m = trunnion_params();
  m.effects.workpiece_deflection = {true, {0.04, 17.0, {0.0, 0.0, 0.0}, {0.0, 0.0, 1.0}}};
  const MachineOutputs r = rigid(m, kTilted);
  const Vector3d f(-2.0, 1.0, 0.0), contact(0.8, 0.0, 17.0);
  const MachineOutputs out = step_once(m, kTilted, f, contact).out;
  const Vector3d want = f / 0.04 * 1e-3;
  EXPECT_LT((v3(out.workpiece_deflection_mm) - want).norm(), 1e-15);
  EXPECT_LT((v3(out.tcp_true) - v3(r.tcp_true) - want).norm(), 1e-12);
  EXPECT_EQ(r.tool_axis_true, out.tool_axis_true) << "the part's rotation is not modelled";
  EXPECT_EQ(0.0, v3(out.tool_deflection_mm).norm());
  // Both effects add at the TCP.
  m.effects.tool_deflection = {true, {2.0, 15.0}};
  const Vector3d f_across = f - v3(r.tool_axis_true) * v3(r.tool_axis_true).dot(f);
  const MachineOutputs both = step_once(m, kTilted, f, v3(r.tcp_true)).out;
  const Vector3d part = v3(both.workpiece_deflection_mm);
  EXPECT_LT((v3(both.tool_deflection_mm) - f_across / 2.0 * 1e-3).norm(), 1e-15);
  EXPECT_LT((v3(both.tcp_true) - v3(r.tcp_true) - f_across / 2.0 * 1e-3 - part).norm(), 1e-12);
}

TEST(Deflection, OffByDefaultAndWhenDisabled) {
  const MachineDescription d = parse_machine_description(
      R"({"truecut_machine": 1, "joints": {"x": {"min_mm": -500, "max_mm": 500},
          "y": {"min_mm": -500, "max_mm": 500}, "z": {"min_mm": -500, "max_mm": 500}},
          "kinematics": {"type": "xyzac-trt", "tool": {"length_mm": 50}}})",
      "m.json");
  EXPECT_EQ(nullptr, d.machine.effects.tool_deflection.active());
  EXPECT_EQ(nullptr, d.machine.effects.workpiece_deflection.active());
  const std::array<double, kJointCount> pos = {10.0, 20.0, -30.0, 0.0, 0.0};
  const MachineOutputs r = rigid(d.machine, pos);
  const MachineOutputs out =
      step_once(d.machine, pos, Vector3d(100, -50, 20), Vector3d(10, 20, 20)).out;
  EXPECT_TRUE(bitwise_equal(r, out));
  MachineParams off = trunnion_params();
  off.effects.tool_deflection = {false, {0.1, 10.0}};
  off.effects.workpiece_deflection = {false, {0.01, 10.0, {}, {0, 0, 1}}};
  EXPECT_TRUE(bitwise_equal(
      rigid(off, kTilted), step_once(off, kTilted, Vector3d(100, -50, 20), Vector3d(0, 0, 5)).out));
  // A default input (no force) bends nothing when the effects are on.
  MachineParams on = off;
  on.effects.tool_deflection.enabled = on.effects.workpiece_deflection.enabled = true;
  EXPECT_TRUE(bitwise_equal(rigid(on, kTilted),
                            step_once(on, kTilted, Vector3d::Zero(), Vector3d::Zero()).out));
}

TEST(Deflection, NonFiniteForceIsHeldAndFaults) {
  MachineParams m = with_tool_deflection(2.0, 15.0);
  m.effects.workpiece_deflection = {true, {0.04, 17.0, {0.0, 0.0, 0.0}, {0.0, 0.0, 1.0}}};
  MachineModel model(m);
  MachineState st;
  MachineInputs in;
  in.pos_cmd = kTilted;
  in.cut_force_n = {10.0, -5.0, 2.0};
  in.cut_contact_mm = {0.0, 0.0, 8.0};
  MachineOutputs good, held;
  model.step(st, in, 1e-3, good);
  EXPECT_FALSE(good.fault);
  in.cut_force_n[1] = std::nan("");
  in.cut_contact_mm[2] = INFINITY;
  model.step(st, in, 1e-3, held);
  EXPECT_TRUE(held.fault);
  EXPECT_EQ(good.tcp_true, held.tcp_true);
  EXPECT_EQ(good.tool_deflection_mm, held.tool_deflection_mm);
  EXPECT_EQ(good.workpiece_deflection_mm, held.workpiece_deflection_mm);
}

TEST(Deflection, RunsAreBitForBitRepeatable) {
  MachineParams m = with_tool_deflection(1.5, 20.0);
  m.effects.workpiece_deflection = {true, {0.04, 17.0, {120.0, -40.0, -250.0}, {0, 0, 1}}};
  enable_servo_lag(m, kX, 30.0, 0.5);
  auto path = [](double t) {
    MachineInputs in;
    in.pos_cmd = {150.0 + 20.0 * std::sin(3.0 * t), 20.0, -90.0, 35.0 * t, 200.0};
    in.cut_force_n = {40.0 * std::cos(7.0 * t), 25.0 * std::sin(5.0 * t), 10.0};
    in.cut_contact_mm = {120.0, -40.0, -240.0 + 5.0 * t};
    return in;
  };
  const Trace a = run(m, 1e-3, 2000, path), b = run(m, 1e-3, 2000, path);
  double max_tool = 0.0, max_part = 0.0;
  for (size_t k = 0; k < a.out.size(); ++k) {
    ASSERT_TRUE(bitwise_equal(a.out[k], b.out[k])) << k;
    max_tool = std::max(max_tool, v3(a.out[k].tool_deflection_mm).norm());
    max_part = std::max(max_part, v3(a.out[k].workpiece_deflection_mm).norm());
  }
  EXPECT_GT(max_tool, 0.01);
  EXPECT_GT(max_part, 0.01);
}

// --- The machine description --------------------------------------------

namespace {

const char* kDeflecting = R"({"truecut_machine": 1,
  "joints": {"x": {"min_mm": -1000, "max_mm": 1000}, "y": {"min_mm": -1000, "max_mm": 1000},
             "z": {"min_mm": -1000, "max_mm": 1000}, "a": {"min_deg": -120, "max_deg": 120},
             "c": {"min_deg": -720, "max_deg": 720}},
  "kinematics": {"type": "xyzac-trt", "x_rot_point_mm": 120, "y_rot_point_mm": -40,
                 "z_rot_point_mm": -250, "y_offset_mm": 30, "z_offset_mm": 60,
                 "tool": {"length_mm": 35, "radius_mm": 1, "corner_radius_mm": 0}},
  "effects": {"tool_deflection": {"enabled": true, "stiffness_n_per_um": 0.033},
              "workpiece_deflection": {"enabled": true, "stiffness_n_per_um": 0.038,
                                       "reference_length_mm": 17,
                                       "clamp_point_mm": [0, 0, 0], "axis": [0, 0, 1]}}})";

std::string error_of(const json& j) {
  try {
    parse_machine_description(j.dump(), "m.json");
  } catch (const MachineDescriptionError& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

TEST(DeflectionJson, ReadsParametersAndDefaults) {
  const MachineParams m = parse_machine_description(kDeflecting, "m.json").machine;
  ASSERT_NE(nullptr, m.effects.tool_deflection.active());
  EXPECT_EQ(0.033, m.effects.tool_deflection.params.stiffness_n_per_um);
  EXPECT_FALSE(m.effects.tool_deflection.params.stickout_mm.has_value());
  EXPECT_EQ(35.0, MachineModel(m).tool_stickout_mm());
  const auto* w = m.effects.workpiece_deflection.active();
  ASSERT_NE(nullptr, w);
  EXPECT_EQ((WorkpieceDeflectionParams{0.038, 17.0, {0, 0, 0}, {0, 0, 1}}), *w);
  json j = json::parse(kDeflecting);
  j["effects"]["workpiece_deflection"].erase("clamp_point_mm");
  j["effects"]["workpiece_deflection"].erase("axis");
  j["effects"]["tool_deflection"]["stickout_mm"] = 22.5;
  const MachineParams d = parse_machine_description(j.dump(), "m.json").machine;
  EXPECT_EQ((WorkpieceDeflectionParams{0.038, 17.0, {0, 0, 0}, {0, 0, 1}}),
            d.effects.workpiece_deflection.params);
  EXPECT_EQ(22.5, d.effects.tool_deflection.params.stickout_mm.value_or(0.0));
}

TEST(DeflectionJson, BadInputNamesFileAndKey) {
  struct Case {
    const char* effect;
    const char* key;
    json value;
    const char* message;
  };
  const Case cases[] = {
      {"tool_deflection", "stiffness_n_per_um", 0,
       "m.json: effects.tool_deflection.stiffness_n_per_um: must be > 0"},
      {"tool_deflection", "stiffness_n_per_um", -2,
       "m.json: effects.tool_deflection.stiffness_n_per_um: must be > 0"},
      {"tool_deflection", "stickout_mm", 0,
       "m.json: effects.tool_deflection.stickout_mm: must be > 0"},
      {"tool_deflection", "compliance_um_per_n", 0.5,
       "m.json: effects.tool_deflection.compliance_um_per_n: unknown key; known: enabled, "
       "stiffness_n_per_um, stickout_mm"},
      {"workpiece_deflection", "stiffness_n_per_um", -0.04,
       "m.json: effects.workpiece_deflection.stiffness_n_per_um: must be > 0"},
      {"workpiece_deflection", "reference_length_mm", 0,
       "m.json: effects.workpiece_deflection.reference_length_mm: must be > 0"},
      {"workpiece_deflection", "axis", json::array({0, 0, 0}),
       "m.json: effects.workpiece_deflection.axis: must not be [0, 0, 0]"},
      {"workpiece_deflection", "axis", json::array({0, 1}),
       "m.json: effects.workpiece_deflection.axis: must be an array of 3 numbers [x, y, z]"},
      {"workpiece_deflection", "clamp_point_mm", json::array({0, "z", 1}),
       "m.json: effects.workpiece_deflection.clamp_point_mm[1]: must be a number"},
      {"workpiece_deflection", "clamp_z_mm", 3,
       "m.json: effects.workpiece_deflection.clamp_z_mm: unknown key; known: enabled, "
       "stiffness_n_per_um, reference_length_mm, clamp_point_mm, axis"},
  };
  for (const Case& c : cases) {
    json j = json::parse(kDeflecting);
    j["effects"][c.effect][c.key] = c.value;
    EXPECT_EQ(c.message, error_of(j));
  }
  json j = json::parse(kDeflecting);
  j["effects"]["tool_deflection"].erase("stiffness_n_per_um");
  EXPECT_EQ("m.json: effects.tool_deflection.stiffness_n_per_um: missing", error_of(j));
  j = json::parse(kDeflecting);
  j["effects"]["workpiece_deflection"].erase("reference_length_mm");
  EXPECT_EQ("m.json: effects.workpiece_deflection.reference_length_mm: missing", error_of(j));
  j = json::parse(kDeflecting);
  j["effects"]["workpiece_deflection"]["enabled"] = "yes";
  EXPECT_EQ("m.json: effects.workpiece_deflection.enabled: must be true or false", error_of(j));
  // Without stickout_mm the cantilever is the tool in the spindle at run
  // time (its length may be 0 in the description).
  j = json::parse(kDeflecting);
  j["kinematics"]["tool"]["length_mm"] = 0;
  EXPECT_EQ("(no error)", error_of(j));
  j["effects"]["tool_deflection"]["stickout_mm"] = 0;
  EXPECT_NE(std::string::npos, error_of(j).find("effects.tool_deflection.stickout_mm"))
      << error_of(j);
}

TEST(DeflectionJson, RoundTripsThroughTheWriter) {
  const MachineDescription d = parse_machine_description(kDeflecting, "m.json");
  const std::string text = format_machine_description(d);
  EXPECT_EQ(d, parse_machine_description(text, "w.json")) << text;
  EXPECT_NE(std::string::npos, text.find("\"clamp_point_mm\": [")) << text;
  EXPECT_EQ(std::string::npos, text.find("stickout_mm")) << "absent stays absent: " << text;

  std::mt19937_64 rng(77);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int trial = 0; trial < 50; ++trial) {
    MachineDescription r = d;
    auto& fx = r.machine.effects;
    fx.tool_deflection = {u(rng) < 0.5, {0.01 + 10 * u(rng), std::nullopt}};
    if (u(rng) < 0.5) fx.tool_deflection.params.stickout_mm = 1 + 60 * u(rng);
    fx.workpiece_deflection = {u(rng) < 0.5,
                               {0.001 + u(rng),
                                1 + 50 * u(rng),
                                {u(rng) * 200 - 100, u(rng) * 200 - 100, u(rng) * 200 - 100},
                                {u(rng) - 0.5, u(rng) - 0.5, u(rng) + 0.1}}};
    const std::string t = format_machine_description(r);
    ASSERT_EQ(r, parse_machine_description(t, "random.json")) << t;
  }
}

// --- The machine_joints component ---------------------------------------

TEST(DeflectionComponent, PinsCarryForceAndDeflections) {
  using namespace truecut::rt::hal;
  const auto dir = truecut::test::scratch_dir();
  const auto machine = dir / "m.json";
  std::ofstream(machine) << kDeflecting;
  const char* outputs[] = {"tool-deflection-x",
                           "tool-deflection-y",
                           "tool-deflection-z",
                           "workpiece-deflection-x",
                           "workpiece-deflection-y",
                           "workpiece-deflection-z",
                           "true-tcp-x",
                           "true-tcp-y",
                           "true-tcp-z",
                           "true-tool-i",
                           "true-tool-j",
                           "true-tool-k"};
  double got[12];
  {
    HalOptions o;
    o.component_path = {truecut::test::component_dir()};
    o.output_dir = dir;
    Hal hal(o);
    load_hal_text(hal,
                  "loadrt threads name1=servo period1=1000000\n"
                  "loadrt machine_joints names=m machine=" +
                      machine.string() +
                      "\nloadrt recorder file=trace.csv columns=tdx,wdx\n"
                      "setp m.x.pos-cmd 0\nsetp m.y.pos-cmd 0\nsetp m.z.pos-cmd 45\n"
                      "setp m.cut-force-x -3\nsetp m.cut-force-y 4\nsetp m.cut-force-z 1\n"
                      "setp m.cut-contact-x 1.8\nsetp m.cut-contact-y 0\n"
                      "setp m.cut-contact-z 12\n"
                      "net tdx m.tool-deflection-x => recorder.0.tdx\n"
                      "net wdx m.workpiece-deflection-x => recorder.0.wdx\n"
                      "addf m.update servo\naddf recorder.0.sample servo\n",
                  "d.hal");
    Executor ex(hal);
    RunLimits lim;
    lim.max_cycles = 5;
    ex.run_simulated(lim);
    for (int i = 0; i < 12; ++i)
      got[i] = hal.get_pin_or_param(std::string("m.") + outputs[i]).f;
  }  // the recorder has written its file

  const MachineParams m = parse_machine_description(kDeflecting, "m.json").machine;
  const std::array<double, kJointCount> pos = {0.0, 0.0, 45.0, 0.0, 0.0};
  const MachineOutputs want = step_once(m, pos, {-3, 4, 1}, {1.8, 0, 12}).out;
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(want.tool_deflection_mm[i], got[i]) << outputs[i];
    EXPECT_EQ(want.workpiece_deflection_mm[i], got[3 + i]) << outputs[3 + i];
    EXPECT_EQ(want.tcp_true[i], got[6 + i]) << outputs[6 + i];
    EXPECT_EQ(want.tool_axis_true[i], got[9 + i]) << outputs[9 + i];
  }
  // At A = C = 0 the tip is at (0, 0, 10); the contact 2 mm above it, 12 mm
  // above the clamp; 5 N across the tool and the shaft.
  const double s_f = 1.0 - 2.0 / 35.0, r = 12.0 / 17.0;
  const double tool = 5.0 / 0.033 * 1e-3 * s_f * s_f * (3.0 - s_f) / 2.0;
  EXPECT_NEAR(tool, v3(want.tool_deflection_mm).norm(), 1e-15);
  EXPECT_NEAR(-3.0 / 5.0 * tool, got[0], 1e-15);
  EXPECT_NEAR(5.0 / 0.038 * 1e-3 * r * r * r, v3(want.workpiece_deflection_mm).norm(), 1e-15);
  // Recorded: the last row's tdx and wdx are the pins' values.
  const std::string trace = truecut::test::read_file(dir / "trace.csv");
  ASSERT_EQ(0u, trace.find("t,tdx,wdx\n")) << trace;
  const auto last = trace.rfind('\n', trace.size() - 2) + 1;
  const auto c1 = trace.find(',', last), c2 = trace.find(',', c1 + 1);
  EXPECT_EQ(got[0], std::stod(trace.substr(c1 + 1, c2 - c1 - 1))) << trace;
  EXPECT_EQ(got[3], std::stod(trace.substr(c2 + 1))) << trace;
}

namespace truecut::sim {
namespace {

// The tool in the spindle comes from the inputs (tool changes during a
// program); the effects' tool errors apply to it.
TEST(MachineToolInUse, InputToolReplacesTheDescriptionsTool) {
  MachineParams p;
  for (auto& j : p.joints) {
    j.present = true;
    j.min = -1000;
    j.max = 1000;
  }
  p.effects.tool_radius_error.enabled = true;
  p.effects.tool_radius_error.params.radius_mm = -0.1;
  p.effects.tool_length_error.enabled = true;
  p.effects.tool_length_error.params.length_mm = 0.02;
  const MachineModel model(p);
  MachineState st;
  MachineInputs in;
  in.pos_cmd = {10, 20, 100, 0, 0};
  in.tool_given = true;
  in.tool = {35.0, 3.0, 3.0};  // a ball end mill of radius 3
  MachineOutputs out;
  model.step(st, in, 0.001, out);
  EXPECT_DOUBLE_EQ(35.02, out.tool_true.length_mm);
  EXPECT_DOUBLE_EQ(2.9, out.tool_true.radius_mm);
  EXPECT_DOUBLE_EQ(2.9, out.tool_true.corner_radius_mm);  // a ball stays a ball
  EXPECT_NEAR(100 - 35.02, out.tcp_true[2], 1e-12);       // tip below the gauge point
  EXPECT_FALSE(out.fault);

  MachineInputs bad = in;
  bad.tool.length_mm = std::numeric_limits<double>::quiet_NaN();
  model.step(st, bad, 0.001, out);
  EXPECT_TRUE(out.fault);
  EXPECT_TRUE(std::isfinite(out.tcp_true[2]));
}

}  // namespace
}  // namespace truecut::sim
