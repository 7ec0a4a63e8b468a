// Writes the machine description JSON: every parameter explicit, keys in the
// documented order, numbers in the shortest form that reads back exactly.
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>

#include "machine_description_keys.hpp"
#include "truecut/sim/machine_description.hpp"

namespace truecut::sim {

namespace {

using Json = nlohmann::ordered_json;

template <class Axis, class F>
void write_per_axis(Json& effects, const char* name, const PerAxisEffect<Axis>& e, F&& axis_json) {
  bool any = e.enabled;
  for (const auto& a : e.axes)
    any = any || a.has_value();
  if (!any) return;
  Json out = Json::object();
  out["enabled"] = e.enabled;
  for (int j = 0; j < kJointCount; ++j)
    if (e.axes[j]) out[std::string(kJointNames[j])] = axis_json(*e.axes[j], j);
  effects[name] = out;
}

Json effects_json(const Effects& fx) {
  Json e = Json::object();
  write_per_axis(e, "servo_lag", fx.servo_lag, [](const ServoLagAxis& a, int) {
    return Json{{"kv_per_s", a.kv_per_s}, {"ff1", a.ff1}};
  });
  write_per_axis(e, "backlash", fx.backlash, [](const BacklashAxis& a, int j) {
    return Json{{"play_" + std::string(joint_unit(j)), a.play}};
  });
  write_per_axis(e, "reversal_spike", fx.reversal_spike, [](const ReversalSpikeAxis& a, int j) {
    const auto k = detail::friction_keys(j);
    return Json{{k[0], a.coulomb}, {k[1], a.viscous}};
  });
  write_per_axis(e, "pitch_error", fx.pitch_error, [](const PitchErrorAxis& a, int) {
    return Json{{"scale_um_per_m", a.scale_um_per_m},
                {"reference_mm", a.reference_mm},
                {"periodic_amplitude_um", a.periodic_amplitude_um},
                {"periodic_period_mm", a.periodic_period_mm},
                {"periodic_phase_deg", a.periodic_phase_deg}};
  });
  write_per_axis(e, "thermal_drift", fx.thermal_drift, [](const ThermalDriftAxis& a, int) {
    return Json{{"gain_mm", a.gain_mm},
                {"tau_s", a.tau_s},
                {"driver", a.driver == ThermalDriver::kTime ? "time" : "spindle_power"},
                {"reference_power_kw", a.reference_power_kw}};
  });
  if (fx.squareness.enabled || fx.squareness.params != SquarenessParams{}) {
    const auto& s = fx.squareness.params;
    e["squareness"] = Json{{"enabled", fx.squareness.enabled},
                           {"xy_urad", s.xy_urad},
                           {"yz_urad", s.yz_urad},
                           {"zx_urad", s.zx_urad}};
  }
  if (fx.straightness.enabled || fx.straightness.params != StraightnessParams{}) {
    Json s = Json{{"enabled", fx.straightness.enabled}};
    for (int i = 0; i < kStraightnessCount; ++i)
      if (const auto& c = fx.straightness.params.components[i])
        s[kStraightnessNames[i]] = Json{{"quadratic_um_per_m2", c->quadratic_um_per_m2},
                                        {"cubic_um_per_m3", c->cubic_um_per_m3},
                                        {"reference_mm", c->reference_mm}};
    e["straightness"] = s;
  }
  if (fx.rotary_location.enabled || fx.rotary_location.params != RotaryLocationParams{}) {
    const auto& a = fx.rotary_location.params.a;
    const auto& c = fx.rotary_location.params.c;
    e["rotary_location"] = Json{{"enabled", fx.rotary_location.enabled},
                                {"a", Json{{"e_y0a_um", a.e_y0a_um},
                                           {"e_z0a_um", a.e_z0a_um},
                                           {"e_b0a_urad", a.e_b0a_urad},
                                           {"e_c0a_urad", a.e_c0a_urad},
                                           {"e_a0a_urad", a.e_a0a_urad}}},
                                {"c", Json{{"e_x0c_um", c.e_x0c_um},
                                           {"e_y0c_um", c.e_y0c_um},
                                           {"e_a0c_urad", c.e_a0c_urad},
                                           {"e_b0c_urad", c.e_b0c_urad},
                                           {"e_c0c_urad", c.e_c0c_urad}}}};
  }
  if (fx.tool_length_error.enabled || fx.tool_length_error.params != ToolLengthErrorParams{})
    e["tool_length_error"] = Json{{"enabled", fx.tool_length_error.enabled},
                                  {"length_mm", fx.tool_length_error.params.length_mm}};
  if (fx.tool_radius_error.enabled || fx.tool_radius_error.params != ToolRadiusErrorParams{})
    e["tool_radius_error"] =
        Json{{"enabled", fx.tool_radius_error.enabled},
             {"radius_mm", fx.tool_radius_error.params.radius_mm},
             {"corner_radius_mm", fx.tool_radius_error.params.corner_radius_mm}};
  if (fx.tool_deflection.enabled || fx.tool_deflection.params != ToolDeflectionParams{}) {
    const auto& p = fx.tool_deflection.params;
    Json t =
        Json{{"enabled", fx.tool_deflection.enabled}, {"stiffness_n_per_um", p.stiffness_n_per_um}};
    if (p.stickout_mm) t["stickout_mm"] = *p.stickout_mm;  // absent: the tool length
    e["tool_deflection"] = t;
  }
  if (fx.workpiece_deflection.enabled ||
      fx.workpiece_deflection.params != WorkpieceDeflectionParams{}) {
    const auto& p = fx.workpiece_deflection.params;
    auto xyz = [](const std::array<double, 3>& v) { return Json::array({v[0], v[1], v[2]}); };
    e["workpiece_deflection"] = Json{{"enabled", fx.workpiece_deflection.enabled},
                                     {"stiffness_n_per_um", p.stiffness_n_per_um},
                                     {"reference_length_mm", p.reference_length_mm},
                                     {"clamp_point_mm", xyz(p.clamp_point_mm)},
                                     {"axis", xyz(p.axis)}};
  }
  return e;
}

Json kinematics_json(const KinematicsParams& k) {
  return Json{{"type", "xyzac-trt"},
              {"x_rot_point_mm", k.ac.x_rot_point_mm},
              {"y_rot_point_mm", k.ac.y_rot_point_mm},
              {"z_rot_point_mm", k.ac.z_rot_point_mm},
              {"y_offset_mm", k.ac.y_offset_mm},
              {"z_offset_mm", k.ac.z_offset_mm},
              {"conventional_directions", k.ac.conventional_directions},
              {"tool", Json{{"length_mm", k.tool.length_mm},
                            {"radius_mm", k.tool.radius_mm},
                            {"corner_radius_mm", k.tool.corner_radius_mm}}}};
}

}  // namespace

std::string format_machine_description(const MachineDescription& d) {
  Json root = Json::object();
  root["truecut_machine"] = 1;
  if (!d.name.empty()) root["name"] = d.name;
  Json joints = Json::object();
  for (int j = 0; j < kJointCount; ++j) {
    const JointParams& p = d.machine.joints[j];
    if (!p.present) continue;
    const std::string u(joint_unit(j));
    const auto k = detail::drive_keys(j);
    joints[std::string(kJointNames[j])] = Json{{"min_" + u, p.min},
                                               {"max_" + u, p.max},
                                               {"drive", Json{{k[0], p.drive.vel_bandwidth_hz},
                                                              {k[1], p.drive.vel_integral_time_s},
                                                              {k[2], p.drive.inertia},
                                                              {k[3], p.drive.max_accel},
                                                              {k[4], p.drive.encoder_resolution}}}};
  }
  root["joints"] = joints;
  if (d.machine.kinematics != KinematicsParams{})
    root["kinematics"] = kinematics_json(d.machine.kinematics);
  root["effects"] = effects_json(d.machine.effects);
  return root.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) + "\n";
}

void write_machine_description(const std::filesystem::path& file, const MachineDescription& d) {
  const std::string text = format_machine_description(d);
  std::filesystem::path tmp = file;
  tmp += ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out << text;
    out.flush();
    if (!out) {
      const std::string why = std::strerror(errno);
      std::error_code ec;
      std::filesystem::remove(tmp, ec);
      throw MachineDescriptionError(file.string() + ": cannot write: " + why);
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, file, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw MachineDescriptionError(file.string() + ": cannot write: " + ec.message());
  }
}

}  // namespace truecut::sim
