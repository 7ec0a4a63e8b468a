// Machine description JSON: defaults, round trip, and errors that name the
// file and the key path.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <random>
#include <string>

#include "test_names.hpp"
#include "test_paths.hpp"
#include "truecut/sim/machine_description.hpp"

using namespace truecut::sim;
using nlohmann::json;

namespace {

const char* kBase = R"({
  "truecut_machine": 1,
  "name": "test mill",
  "joints": {
    "x": {"min_mm": -300, "max_mm": 300},
    "y": {"min_mm": -200, "max_mm": 200, "drive": {"mass_kg": 700, "encoder_resolution_mm": 0}},
    "z": {"min_mm": -400, "max_mm": 0},
    "a": {"min_deg": -120, "max_deg": 30},
    "c": {"min_deg": -36000, "max_deg": 36000, "drive": {"inertia_kg_m2": 3.5}}
  },
  "kinematics": {"type": "xyzac-trt", "x_rot_point_mm": 120, "y_rot_point_mm": -40,
                 "z_rot_point_mm": -250, "y_offset_mm": 30, "z_offset_mm": 60,
                 "tool": {"length_mm": 80, "radius_mm": 3, "corner_radius_mm": 3}},
  "effects": {
    "servo_lag": {"enabled": true, "x": {"kv_per_s": 30}, "c": {"kv_per_s": 20, "ff1": 0.5}},
    "backlash": {"enabled": true, "x": {"play_mm": 0.01}, "c": {"play_deg": 0.002}},
    "reversal_spike": {"enabled": false, "y": {"coulomb_n": 100}},
    "pitch_error": {"enabled": true, "x": {"scale_um_per_m": 12}},
    "thermal_drift": {"enabled": true,
                      "z": {"gain_mm": -0.02, "tau_s": 900, "driver": "spindle_power",
                            "reference_power_kw": 12}},
    "squareness": {"enabled": true, "xy_urad": 30},
    "straightness": {"enabled": true, "eyx": {"quadratic_um_per_m2": 20}},
    "rotary_location": {"enabled": true, "a": {"e_y0a_um": 5, "e_b0a_urad": -12},
                        "c": {"e_x0c_um": 8, "e_c0c_urad": 30}},
    "tool_length_error": {"enabled": true, "length_mm": 0.04},
    "tool_radius_error": {"enabled": true, "radius_mm": -0.1}
  }
})";

std::string error_of(const std::string& text) {
  try {
    parse_machine_description(text, "m.json");
  } catch (const MachineDescriptionError& e) {
    return e.what();
  }
  return "(no error)";
}

std::string error_of(const json& j) {
  return error_of(j.dump());
}

}  // namespace

TEST(MachineDescription, ReadsValuesAndDefaults) {
  auto d = parse_machine_description(kBase, "m.json");
  EXPECT_EQ("test mill", d.name);
  const auto& m = d.machine;
  EXPECT_TRUE(m.joints[kX].present);
  EXPECT_EQ(-300.0, m.joints[kX].min);
  EXPECT_EQ(700.0, m.joints[kY].drive.inertia);
  EXPECT_EQ(0.0, m.joints[kY].drive.encoder_resolution);
  EXPECT_EQ(default_drive(kX).vel_bandwidth_hz, m.joints[kY].drive.vel_bandwidth_hz);
  EXPECT_EQ(3.5, m.joints[kC].drive.inertia);
  ASSERT_NE(nullptr, m.effects.servo_lag.active(kX));
  EXPECT_EQ(0.0, m.effects.servo_lag.active(kX)->ff1);
  EXPECT_EQ(0.5, m.effects.servo_lag.active(kC)->ff1);
  EXPECT_EQ(nullptr, m.effects.servo_lag.active(kY));
  EXPECT_EQ(0.002, m.effects.backlash.active(kC)->play);
  EXPECT_EQ(nullptr, m.effects.reversal_spike.active(kY)) << "listed but switched off";
  ASSERT_TRUE(m.effects.reversal_spike.axes[kY].has_value());
  EXPECT_EQ(ThermalDriver::kSpindlePower, m.effects.thermal_drift.active(kZ)->driver);
  EXPECT_EQ(30.0, m.effects.squareness.active()->xy_urad);
  EXPECT_EQ(20.0, m.effects.straightness.active()->components[kEYX]->quadratic_um_per_m2);
}

TEST(MachineDescription, ReadsKinematicsAndPoseEffects) {
  const auto m = parse_machine_description(kBase, "m.json").machine;
  EXPECT_EQ(KinematicsType::kXyzacTrt, m.kinematics.type);
  EXPECT_EQ(120.0, m.kinematics.ac.x_rot_point_mm);
  EXPECT_EQ(-40.0, m.kinematics.ac.y_rot_point_mm);
  EXPECT_EQ(-250.0, m.kinematics.ac.z_rot_point_mm);
  EXPECT_EQ(30.0, m.kinematics.ac.y_offset_mm);
  EXPECT_EQ(60.0, m.kinematics.ac.z_offset_mm);
  EXPECT_FALSE(m.kinematics.ac.conventional_directions);
  EXPECT_EQ((NominalTool{80.0, 3.0, 3.0}), m.kinematics.tool);
  const auto* loc = m.effects.rotary_location.active();
  ASSERT_NE(nullptr, loc);
  EXPECT_EQ((RotaryLocationA{5.0, 0.0, -12.0, 0.0, 0.0}), loc->a);
  EXPECT_EQ((RotaryLocationC{8.0, 0.0, 0.0, 0.0, 30.0}), loc->c);
  EXPECT_EQ(0.04, m.effects.tool_length_error.active()->length_mm);
  EXPECT_EQ((ToolRadiusErrorParams{-0.1, 0.0}), *m.effects.tool_radius_error.active());
}

TEST(MachineDescription, KinematicsDefaultsToZeros) {
  auto d = parse_machine_description(
      R"({"truecut_machine": 1, "joints": {"x": {"min_mm": 0, "max_mm": 1},
          "y": {"min_mm": 0, "max_mm": 1}, "z": {"min_mm": 0, "max_mm": 1}},
          "kinematics": {"type": "xyzac-trt", "conventional_directions": true,
                         "tool": {"radius_mm": 2}}})",
      "m.json");
  KinematicsParams want;
  want.ac.conventional_directions = true;
  want.tool.radius_mm = 2.0;
  EXPECT_EQ(want, d.machine.kinematics);
  // Written back with every key explicit, and left out when all default.
  const auto text = format_machine_description(d);
  EXPECT_NE(std::string::npos, text.find("\"z_offset_mm\": 0")) << text;
  d.machine.kinematics = {};
  EXPECT_EQ(std::string::npos, format_machine_description(d).find("kinematics"));
}

TEST(MachineDescription, WithoutEffectsEverythingIsOff) {
  auto d = parse_machine_description(
      R"({"truecut_machine": 1, "joints": {"x": {"min_mm": 0, "max_mm": 1},
          "y": {"min_mm": 0, "max_mm": 1}, "z": {"min_mm": 0, "max_mm": 1}}})",
      "m.json");
  EXPECT_EQ(Effects{}, d.machine.effects);
  EXPECT_EQ(KinematicsParams{}, d.machine.kinematics);
  EXPECT_FALSE(d.machine.joints[kA].present);
  EXPECT_EQ(0.0, d.machine.joints[kA].max) << "an absent joint has no travel";
}

TEST(MachineDescription, RoundTripsThroughTheWriter) {
  auto d = parse_machine_description(kBase, "m.json");
  auto text = format_machine_description(d);
  EXPECT_EQ(d, parse_machine_description(text, "written.json")) << text;
  EXPECT_EQ(text, format_machine_description(parse_machine_description(text, "w.json")));

  auto file = truecut::test::scratch_dir() / "fitted.json";
  write_machine_description(file, d);
  EXPECT_FALSE(std::filesystem::exists(file.string() + ".tmp"));
  EXPECT_EQ(d, read_machine_description(file));
}

TEST(MachineDescription, RandomParametersRoundTripExactly) {
  std::mt19937_64 rng(4242);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::bernoulli_distribution coin(0.5);
  for (int trial = 0; trial < 50; ++trial) {
    MachineDescription d;
    d.name = "trial " + std::to_string(trial);
    auto& m = d.machine;
    for (int j = 0; j < kJointCount; ++j) {
      auto& jp = m.joints[j];
      jp.drive = default_drive(j);
      if (j >= 3 && coin(rng)) continue;
      jp.present = true;
      jp.min = -1000 * u(rng);
      jp.max = 1000 * u(rng) + 1e-3;
      jp.drive.inertia = 1 + 900 * u(rng);
      jp.drive.encoder_resolution = 1e-4 * u(rng);
      if (coin(rng)) m.effects.servo_lag.axes[j] = ServoLagAxis{1 + 99 * u(rng), 1.5 * u(rng)};
      if (coin(rng)) m.effects.backlash.axes[j] = BacklashAxis{0.05 * u(rng)};
      if (m.effects.servo_lag.axes[j] && coin(rng))
        m.effects.reversal_spike.axes[j] = ReversalSpikeAxis{500 * u(rng), 0.1 * u(rng)};
      if (j < 3 && coin(rng))
        m.effects.pitch_error.axes[j] =
            PitchErrorAxis{u(rng) * 40 - 20, u(rng), u(rng) * 5, 1 + u(rng) * 20, u(rng) * 360};
      if (j < 3 && coin(rng))
        m.effects.thermal_drift.axes[j] = ThermalDriftAxis{
            u(rng) * 0.1 - 0.05, 1 + u(rng) * 3600,
            coin(rng) ? ThermalDriver::kTime : ThermalDriver::kSpindlePower, 1 + u(rng) * 20};
    }
    m.effects.servo_lag.enabled = m.effects.reversal_spike.enabled = coin(rng);
    m.effects.backlash.enabled = coin(rng);
    m.effects.pitch_error.enabled = coin(rng);
    m.effects.thermal_drift.enabled = coin(rng);
    m.effects.squareness = {coin(rng), {u(rng) * 100 - 50, u(rng) * 100 - 50, u(rng)}};
    m.effects.straightness.enabled = coin(rng);
    for (auto& c : m.effects.straightness.params.components)
      if (coin(rng)) c = StraightnessComponent{u(rng) * 50, u(rng) * 50 - 25, u(rng) * 100};
    if (coin(rng)) {
      auto& k = m.kinematics;
      k = {};
      k.ac.x_rot_point_mm = u(rng) * 600 - 300;
      k.ac.y_rot_point_mm = u(rng) * 600 - 300;
      k.ac.z_rot_point_mm = u(rng) * 600 - 300;
      k.ac.y_offset_mm = u(rng) * 100 - 50;
      k.ac.z_offset_mm = u(rng) * 100 - 50;
      k.ac.conventional_directions = coin(rng);
      k.tool.length_mm = u(rng) * 200;
      k.tool.radius_mm = u(rng) * 10;
      k.tool.corner_radius_mm = coin(rng) ? k.tool.radius_mm : u(rng) * k.tool.radius_mm;
    }
    if (m.joints[kA].present && m.joints[kC].present && coin(rng))
      m.effects.rotary_location = {
          coin(rng),
          {{u(rng) * 40 - 20, u(rng) * 40 - 20, u(rng) * 100 - 50, u(rng) * 100 - 50, u(rng) * 99},
           {u(rng) * 40 - 20, u(rng) * 40 - 20, u(rng) * 100 - 50, u(rng) * 100 - 50, u(rng)}}};
    if (coin(rng)) m.effects.tool_length_error = {coin(rng), {u(rng) * 0.4 - 0.2}};
    if (coin(rng)) m.effects.tool_radius_error = {coin(rng), {u(rng) * 0.1, 0.0}};
    const auto text = format_machine_description(d);
    ASSERT_EQ(d, parse_machine_description(text, "random.json")) << text;
  }
}

TEST(MachineDescription, ExampleMachinesAreValid) {
  int n = 0;
  for (const auto& f :
       std::filesystem::directory_iterator(truecut::test::source_dir() / "examples/machines")) {
    if (f.path().extension() != ".json") continue;
    EXPECT_NO_THROW(read_machine_description(f.path())) << f.path();
    ++n;
  }
  EXPECT_GE(n, 1);
}

TEST(MachineDescription, UnreadableFileIsNamed) {
  try {
    read_machine_description("/nonexistent/machine.json");
    FAIL();
  } catch (const MachineDescriptionError& e) {
    EXPECT_EQ(0u, std::string(e.what()).find(
                      "/nonexistent/machine.json: cannot open the machine description"));
  }
}

struct BadCase {
  const char* pointer;  // JSON pointer to change
  json value;           // new value; null + remove=true deletes the key
  bool remove;
  const char* message;  // expected start of the message after "m.json: "
};

class BadInput : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadInput, MessageNamesFileAndKey) {
  const BadCase& c = GetParam();
  json j = json::parse(kBase);
  const json::json_pointer ptr(c.pointer);
  if (c.remove)
    j[ptr.parent_pointer()].erase(ptr.back());
  else
    j[ptr] = c.value;
  const std::string msg = error_of(j);
  EXPECT_EQ(0u, msg.find(std::string("m.json: ") + c.message)) << msg;
}

INSTANTIATE_TEST_SUITE_P(
    Cases, BadInput,
    ::testing::Values(
        BadCase{"/effects/backlash/x/play_mm", -0.01, false,
                "effects.backlash.x.play_mm: must be >= 0"},
        BadCase{"/effects/backlsh", json::object(), false,
                "effects.backlsh: unknown effect; known: servo_lag, backlash, reversal_spike, "
                "pitch_error, thermal_drift, squareness, straightness, rotary_location, "
                "tool_length_error, tool_radius_error, tool_deflection, workpiece_deflection"},
        BadCase{"/effects/servo_lag/x/kv", 3, false,
                "effects.servo_lag.x.kv: unknown parameter; known: kv_per_s, ff1"},
        BadCase{"/effects/thermal_drift/z/tau_s", -5, false,
                "effects.thermal_drift.z.tau_s: must be > 0"},
        BadCase{"/effects/servo_lag/x/kv_per_s", "fast", false,
                "effects.servo_lag.x.kv_per_s: must be a number"},
        BadCase{"/effects/servo_lag/x/ff1", 2, false,
                "effects.servo_lag.x.ff1: must be in 0 .. 1.5"},
        BadCase{"/effects/servo_lag/enabled", 1, false,
                "effects.servo_lag.enabled: must be true or false"},
        BadCase{"/effects/backlash/enabled", nullptr, true, "effects.backlash.enabled: missing"},
        BadCase{"/effects/backlash/c/play_mm", 0.1, false,
                "effects.backlash.c.play_mm: unknown parameter; known: play_deg"},
        BadCase{"/effects/pitch_error/a", json::object(), false,
                "effects.pitch_error.a: unknown key; known: enabled, x, y, z"},
        BadCase{"/effects/pitch_error/x/periodic_amplitude_um", 2, false,
                "effects.pitch_error.x.periodic_period_mm: missing"},
        BadCase{"/effects/reversal_spike/enabled", true, false,
                "effects.reversal_spike.y: friction acts through the servo loop"},
        BadCase{"/effects/thermal_drift/z/driver", "coolant", false,
                "effects.thermal_drift.z.driver: unknown driver 'coolant'; known: time, "
                "spindle_power"},
        BadCase{"/effects/thermal_drift/z/reference_power_kw", nullptr, true,
                "effects.thermal_drift.z.reference_power_kw: missing"},
        BadCase{"/effects/squareness/xy_urad", true, false,
                "effects.squareness.xy_urad: must be a number"},
        BadCase{"/effects/straightness/eyy", json::object(), false,
                "effects.straightness.eyy: unknown key; known: enabled, eyx, ezx, exy, ezy, exz, "
                "eyz"},
        BadCase{"/effects/servo_lag/x", 30, false, "effects.servo_lag.x: must be an object"},
        BadCase{"/truecut_machine", 2, false, "truecut_machine: unsupported version 2"},
        BadCase{"/truecut_machine", nullptr, true, "truecut_machine: missing"},
        BadCase{"/name", 5, false, "name: must be a string"},
        BadCase{"/efects", json::object(), false,
                "efects: unknown key; known: truecut_machine, name, joints, kinematics, effects"},
        BadCase{"/joints/z", nullptr, true, "joints.z: missing"},
        BadCase{"/joints/b", json::object(), false,
                "joints.b: unknown joint; known: x, y, z, a, c"},
        BadCase{"/joints/x/max_mm", -400, false,
                "joints.x.max_mm: must be greater than min_mm (-300)"},
        BadCase{"/joints/a/drive", json{{"mass_kg", 5}}, false,
                "joints.a.drive.mass_kg: unknown parameter; known: vel_bandwidth_hz, "
                "vel_integral_time_s, inertia_kg_m2, max_accel_deg_per_s2, "
                "encoder_resolution_deg"},
        BadCase{"/joints/x/drive", json{{"vel_integral_time_s", 0}}, false,
                "joints.x.drive.vel_integral_time_s: must be > 0"},
        BadCase{"/joints/c", nullptr, true, "effects.servo_lag.c: joint c is not listed in joints"},
        BadCase{"/kinematics/type", "xyzbc-trt", false,
                "kinematics.type: unknown kinematics type 'xyzbc-trt'; known: xyzac-trt"},
        BadCase{"/kinematics/type", nullptr, true, "kinematics.type: missing"},
        BadCase{"/kinematics/x_rot_point", 3, false,
                "kinematics.x_rot_point: unknown key; known: type, x_rot_point_mm, "
                "y_rot_point_mm, z_rot_point_mm, y_offset_mm, z_offset_mm, "
                "conventional_directions, tool"},
        BadCase{"/kinematics/y_offset_mm", "far", false,
                "kinematics.y_offset_mm: must be a number"},
        BadCase{"/kinematics/conventional_directions", 1, false,
                "kinematics.conventional_directions: must be true or false"},
        BadCase{"/kinematics/tool/radius_mm", -1, false, "kinematics.tool.radius_mm: must be >= 0"},
        BadCase{"/kinematics/tool/diameter_mm", 6, false,
                "kinematics.tool.diameter_mm: unknown parameter; known: length_mm, radius_mm, "
                "corner_radius_mm"},
        BadCase{"/kinematics/tool/corner_radius_mm", 4, false,
                "kinematics.tool.corner_radius_mm: must not exceed radius_mm (3)"},
        BadCase{"/kinematics/tool/length_mm", -80, false,
                "kinematics.tool.length_mm: must be >= 0"},
        BadCase{"/effects/rotary_location/c/e_x0c_mm", 0.01, false,
                "effects.rotary_location.c.e_x0c_mm: unknown parameter; known: e_x0c_um, "
                "e_y0c_um, e_a0c_urad, e_b0c_urad, e_c0c_urad"},
        BadCase{"/effects/rotary_location/a/e_x0c_um", 1, false,
                "effects.rotary_location.a.e_x0c_um: unknown parameter; known: e_y0a_um, "
                "e_z0a_um, e_b0a_urad, e_c0a_urad, e_a0a_urad"},
        BadCase{"/effects/rotary_location/b", json::object(), false,
                "effects.rotary_location.b: unknown key; known: enabled, a, c"},
        BadCase{"/effects/rotary_location/enabled", nullptr, true,
                "effects.rotary_location.enabled: missing"},
        BadCase{"/effects/rotary_location/c/e_c0c_urad", "1 arcsec", false,
                "effects.rotary_location.c.e_c0c_urad: must be a number"},
        BadCase{"/joints/a", nullptr, true,
                "effects.rotary_location.a: joint a is not listed in joints"},
        BadCase{"/effects/tool_length_error/length", 0.1, false,
                "effects.tool_length_error.length: unknown key; known: enabled, length_mm"},
        BadCase{"/effects/tool_length_error/length_mm", "long", false,
                "effects.tool_length_error.length_mm: must be a number"},
        BadCase{"/effects/tool_radius_error/radius_mm", -3.5, false,
                "effects.tool_radius_error.radius_mm: makes the true radius -0.5 negative "
                "(kinematics.tool.radius_mm is 3)"},
        BadCase{"/effects/tool_radius_error/corner_radius_mm", 0.1, false,
                "effects.tool_radius_error.corner_radius_mm: must be 0: the nominal tool is a "
                "ball end mill"},
        BadCase{"/effects/tool_radius_error/enabled", "on", false,
                "effects.tool_radius_error.enabled: must be true or false"}),
    // The JSON pointer changed, e.g. "effects_backlash_x_play_mm" or "joints_z_removed".
    [](const ::testing::TestParamInfo<BadCase>& info) {
      return truecut::test::test_name(info.param.pointer) + (info.param.remove ? "_removed" : "");
    });

TEST(BadInputJson, RealCornerRadiusMustFitTheRealRadius) {
  json j = json::parse(kBase);
  j["kinematics"]["tool"]["corner_radius_mm"] = 1.0;  // a bull-nose mill
  j["effects"]["tool_radius_error"]["radius_mm"] = -2.5;
  EXPECT_EQ(
      "m.json: effects.tool_radius_error.radius_mm: makes the true corner radius 1 leave 0 .. "
      "0.5 (the true radius)",
      error_of(j));
  j["effects"]["tool_radius_error"]["radius_mm"] = 0.0;
  j["effects"]["tool_radius_error"]["corner_radius_mm"] = -1.5;
  EXPECT_EQ(
      "m.json: effects.tool_radius_error.corner_radius_mm: makes the true corner radius -0.5 "
      "leave 0 .. 3 (the true radius)",
      error_of(j));
  j["effects"]["tool_radius_error"]["corner_radius_mm"] = 0.5;
  EXPECT_EQ("(no error)", error_of(j));
}

TEST(BadInputText, NanInfinityDuplicatesAndSyntax) {
  std::string base = kBase;
  auto with = [&](const std::string& from, const std::string& to) {
    std::string s = base;
    auto pos = s.find(from);
    EXPECT_NE(std::string::npos, pos) << from;
    return s.replace(pos, from.size(), to);
  };
  EXPECT_EQ(0u, error_of(with("\"play_mm\": 0.01", "\"play_mm\": NaN"))
                    .find("m.json: not valid "
                          "JSON: "));
  EXPECT_EQ("m.json: not valid JSON: number overflow parsing '1e999'",
            error_of(with("\"play_mm\": 0.01", "\"play_mm\": 1e999")));
  EXPECT_EQ("m.json: effects.backlash.x: key given twice",
            error_of(with("\"x\": {\"play_mm\": 0.01}",
                          "\"x\": {\"play_mm\": 0.01}, \"x\": {\"play_mm\": 0.02}")));
  const std::string syntax = error_of(with("\"name\": \"test mill\",", "\"name\": \"test mill\""));
  EXPECT_EQ(0u, syntax.find("m.json: not valid JSON: ")) << syntax;
  EXPECT_NE(std::string::npos, syntax.find("line 4")) << syntax;
  EXPECT_EQ("m.json: (top level): must be an object", error_of(std::string("[1, 2]")));
}

// Issue 23: a name that is not UTF-8 (a Latin-1 é) made the writer throw
// nlohmann's type_error instead of writing JSON; it is written as U+FFFD, as
// the other commands' JSON writes such a byte.
TEST(MachineDescription, ANameThatIsNotUtf8IsWrittenAsJson) {
  MachineDescription d;
  d.name = "caf\xe9";
  std::string text;
  ASSERT_NO_THROW(text = format_machine_description(d));
  EXPECT_EQ(json::parse(text)["name"], "caf\xEF\xBF\xBD");
}
