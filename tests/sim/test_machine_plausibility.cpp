// Machine descriptions with absurd values (a unit mix-up, a typo of the
// exponent): every numeric value of a description that switches on every
// effect is replaced in turn by huge and tiny values. Each one is either
// refused, naming its key, or gives a machine whose outputs stay finite over
// its whole travel. Before the plausibility ranges, 1e300 in a pivot or an
// error gave NaN tool-centre points with exit 0.
#include <gtest/gtest.h>

#include <cctype>
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "truecut/sim/machine_description.hpp"
#include "truecut/sim/machine_model.hpp"

using namespace truecut::sim;
using nlohmann::json;

namespace {

// Every effect on, with every parameter it has.
const char* kEverything = R"({
  "truecut_machine": 1,
  "joints": {
    "x": {"min_mm": -300, "max_mm": 300,
          "drive": {"vel_bandwidth_hz": 40, "vel_integral_time_s": 0.01, "mass_kg": 500,
                    "max_accel_mm_per_s2": 5000, "encoder_resolution_mm": 0.0001}},
    "y": {"min_mm": -200, "max_mm": 200},
    "z": {"min_mm": -400, "max_mm": 0},
    "a": {"min_deg": -120, "max_deg": 30},
    "c": {"min_deg": -360, "max_deg": 360,
          "drive": {"inertia_kg_m2": 2, "max_accel_deg_per_s2": 20000}}
  },
  "kinematics": {"type": "xyzac-trt", "x_rot_point_mm": 120, "y_rot_point_mm": -40,
                 "z_rot_point_mm": -250, "y_offset_mm": 30, "z_offset_mm": 60,
                 "tool": {"length_mm": 80, "radius_mm": 3, "corner_radius_mm": 1}},
  "effects": {
    "servo_lag": {"enabled": true, "x": {"kv_per_s": 30, "ff1": 0.9}, "c": {"kv_per_s": 20}},
    "backlash": {"enabled": true, "x": {"play_mm": 0.01}, "c": {"play_deg": 0.002}},
    "reversal_spike": {"enabled": true, "x": {"coulomb_n": 100, "viscous_n_s_per_mm": 0.5}},
    "pitch_error": {"enabled": true,
                    "y": {"scale_um_per_m": 12, "reference_mm": 10, "periodic_amplitude_um": 2,
                          "periodic_period_mm": 5, "periodic_phase_deg": 30}},
    "thermal_drift": {"enabled": true,
                      "z": {"gain_mm": -0.02, "tau_s": 900, "driver": "spindle_power",
                            "reference_power_kw": 12}},
    "squareness": {"enabled": true, "xy_urad": 30, "yz_urad": -10, "zx_urad": 5},
    "straightness": {"enabled": true,
                     "eyx": {"quadratic_um_per_m2": 20, "cubic_um_per_m3": 3, "reference_mm": 1}},
    "rotary_location": {"enabled": true,
                        "a": {"e_y0a_um": 5, "e_z0a_um": 3, "e_b0a_urad": -12, "e_c0a_urad": 4,
                              "e_a0a_urad": 2},
                        "c": {"e_x0c_um": 8, "e_y0c_um": 1, "e_a0c_urad": 6, "e_b0c_urad": 2,
                              "e_c0c_urad": 30}},
    "tool_length_error": {"enabled": true, "length_mm": 0.04},
    "tool_radius_error": {"enabled": true, "radius_mm": -0.1, "corner_radius_mm": 0.05},
    "tool_deflection": {"enabled": true, "stiffness_n_per_um": 2, "stickout_mm": 40},
    "workpiece_deflection": {"enabled": true, "stiffness_n_per_um": 5, "reference_length_mm": 50,
                             "clamp_point_mm": [0, 0, -30], "axis": [0, 0, 1]}
  }
})";

// JSON pointers of every number in `j`.
void numeric_leaves(const json& j, const std::string& at, std::vector<std::string>& out) {
  if (j.is_number()) {
    out.push_back(at);
  } else if (j.is_object()) {
    for (const auto& [k, v] : j.items())
      numeric_leaves(v, at + "/" + k, out);
  } else if (j.is_array()) {
    for (std::size_t i = 0; i < j.size(); ++i)
      numeric_leaves(j[i], at + "/" + std::to_string(i), out);
  }
}

// "/effects/backlash/x/play_mm" -> "effects.backlash.x.play_mm"
std::string key_path(const std::string& pointer) {
  std::string p = pointer.substr(1);
  for (char& c : p)
    if (c == '/') c = '.';
  return p;
}

bool finite3(const std::array<double, 3>& v) {
  return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]);
}

// Runs the machine at the corners of its travel under a cutting force;
// returns what was not finite, or "".
std::string non_finite_output(const MachineParams& params) {
  const MachineModel model(params);
  MachineState state;
  MachineOutputs out;
  for (int corner = 0; corner < 32; ++corner) {
    MachineInputs in;
    for (int j = 0; j < kJointCount; ++j) {
      const JointParams& jp = params.joints[j];
      in.pos_cmd[j] = ((corner >> j) & 1) ? jp.max : jp.min;
    }
    in.spindle_power_kw = 10.0;
    in.cut_force_n = {120.0, -80.0, 300.0};
    in.cut_contact_mm = {10.0, 5.0, -20.0};
    for (int k = 0; k < 20; ++k) {
      model.step(state, in, 1e-3, out);
      if (!finite3(out.tcp_true)) return "tcp_true";
      if (!finite3(out.tool_axis_true)) return "tool_axis_true";
      if (!finite3(out.xyz_true)) return "xyz_true";
      for (int j = 0; j < kJointCount; ++j)
        if (!std::isfinite(out.pos_act[j]) || !std::isfinite(out.pos_true[j]))
          return "joint " + std::to_string(j);
    }
  }
  return "";
}

}  // namespace

TEST(MachinePlausibility, TheDescriptionOfEveryEffectIsValidAndFinite) {
  const MachineDescription d = parse_machine_description(kEverything, "m.json");
  EXPECT_EQ("", non_finite_output(d.machine));
}

TEST(MachinePlausibility, AbsurdValuesAreRefusedByKeyOrStayFinite) {
  const json base = json::parse(kEverything);
  std::vector<std::string> leaves;
  numeric_leaves(base, "", leaves);
  ASSERT_GT(leaves.size(), 60u);
  int refused = 0;
  for (const std::string& leaf : leaves) {
    if (leaf == "/truecut_machine") continue;
    for (const double v : {1e300, -1e300, 1e20, -1e20, 1e9, -1e9}) {
      json j = base;
      j[json::json_pointer(leaf)] = v;
      try {
        const MachineDescription d = parse_machine_description(j.dump(), "m.json");
        EXPECT_EQ("", non_finite_output(d.machine)) << leaf << " = " << v;
      } catch (const MachineDescriptionError& e) {
        ++refused;
        const std::string msg = e.what();
        // An element of [x, y, z] is named by its key and its letter.
        const std::size_t slash = leaf.rfind('/');
        const bool element = std::isdigit(static_cast<unsigned char>(leaf[slash + 1]));
        const std::string key = key_path(element ? leaf.substr(0, slash) : leaf);
        const std::string named =
            element ? key + ": " + "xyz"[leaf[slash + 1] - '0'] + " = " : key + ": ";
        EXPECT_NE(std::string::npos, msg.find(named)) << leaf << " = " << v << ": " << msg;
      }
    }
  }
  // 1e300 and -1e300 at least are refused everywhere.
  EXPECT_GE(refused, 2 * int(leaves.size() - 1));
}

TEST(MachinePlausibility, TheMessageStatesTheValueTheRangeAndWhy) {
  json j = json::parse(kEverything);
  j["kinematics"]["z_rot_point_mm"] = -250000;  // -250 mm written in um
  try {
    parse_machine_description(j.dump(), "m.json");
    FAIL() << "accepted";
  } catch (const MachineDescriptionError& e) {
    EXPECT_STREQ(
        "m.json: kinematics.z_rot_point_mm: -250000 is outside -100000 .. 100000 mm "
        "(no machine is larger than 100 m; check the unit)",
        e.what());
  }
  j = json::parse(kEverything);
  j["effects"]["squareness"]["xy_urad"] = 3e5;
  try {
    parse_machine_description(j.dump(), "m.json");
    FAIL() << "accepted";
  } catch (const MachineDescriptionError& e) {
    EXPECT_NE(std::string::npos,
              std::string(e.what()).find("effects.squareness.xy_urad: 300000 is outside"))
        << e.what();
  }
}
