// Reads the machine description JSON (docs/formats.md, "Machine description").
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

#include "json_node.hpp"
#include "machine_description_keys.hpp"
#include "truecut/sim/machine_description.hpp"
#include "truecut/sim/machine_model.hpp"

namespace truecut::sim {

using detail::format_number;
using detail::JsonNode;

namespace {

double positive(const JsonNode& n) {
  const double v = n.number();
  if (!(v > 0.0)) n.fail("must be > 0");
  return v;
}
double non_negative(const JsonNode& n) {
  const double v = n.number();
  if (!(v >= 0.0)) n.fail("must be >= 0");
  return v;
}
double in_range(const JsonNode& n, double lo, double hi) {
  const double v = n.number();
  if (!(v >= lo && v <= hi)) n.fail("must be in " + format_number(lo) + " .. " + format_number(hi));
  return v;
}

template <class F>
double optional(const JsonNode& obj, const std::string& key, double fallback, F&& read) {
  return obj.has(key) ? read(obj.child(key)) : fallback;
}

double any(const JsonNode& n) {
  return n.number();
}

std::string unit(int joint) {
  return std::string(joint_unit(joint));
}

JointParams read_joint(const JsonNode& n, int j) {
  const std::string u = unit(j);
  n.allow_only({"min_" + u, "max_" + u, "drive"}, "key");
  JointParams p;
  p.present = true;
  p.min = n.child("min_" + u).number();
  p.max = n.child("max_" + u).number();
  if (!(p.min < p.max))
    n.child("max_" + u).fail("must be greater than min_" + u + " (" + format_number(p.min) + ")");
  p.drive = default_drive(j);
  if (n.has("drive")) {
    const JsonNode d = n.child("drive");
    const auto keys = detail::drive_keys(j);
    d.allow_only({keys.begin(), keys.end()}, "parameter");
    DriveParams& dp = p.drive;
    dp.vel_bandwidth_hz = optional(d, keys[0], dp.vel_bandwidth_hz,
                                   [](const JsonNode& v) { return in_range(v, 0.1, 1000.0); });
    dp.vel_integral_time_s = optional(d, keys[1], dp.vel_integral_time_s, positive);
    dp.inertia = optional(d, keys[2], dp.inertia, positive);
    dp.max_accel = optional(d, keys[3], dp.max_accel, positive);
    dp.encoder_resolution = optional(d, keys[4], dp.encoder_resolution, non_negative);
  }
  return p;
}

// An effect object: `enabled` plus one object per axis it applies to.
template <class Axis, class F>
PerAxisEffect<Axis> read_per_axis(const JsonNode& n, int joints, F&& read_axis) {
  std::vector<std::string> known = {"enabled"};
  for (int j = 0; j < joints; ++j)
    known.emplace_back(kJointNames[j]);
  n.allow_only(known, "key");
  PerAxisEffect<Axis> e;
  e.enabled = n.child("enabled").boolean();
  for (int j = 0; j < joints; ++j) {
    const std::string name(kJointNames[j]);
    if (n.has(name)) e.axes[j] = read_axis(n.child(name), j);
  }
  return e;
}

ServoLagAxis read_servo_lag(const JsonNode& n, int) {
  n.allow_only({"kv_per_s", "ff1"}, "parameter");
  ServoLagAxis a;
  a.kv_per_s = in_range(n.child("kv_per_s"), 1e-3, 1000.0);
  a.ff1 = optional(n, "ff1", 0.0, [](const JsonNode& v) { return in_range(v, 0.0, 1.5); });
  return a;
}

BacklashAxis read_backlash(const JsonNode& n, int j) {
  n.allow_only({"play_" + unit(j)}, "parameter");
  return {non_negative(n.child("play_" + unit(j)))};
}

ReversalSpikeAxis read_reversal_spike(const JsonNode& n, int j) {
  const auto keys = detail::friction_keys(j);
  n.allow_only({keys[0], keys[1]}, "parameter");
  ReversalSpikeAxis a;
  a.coulomb = non_negative(n.child(keys[0]));
  a.viscous = optional(n, keys[1], 0.0, non_negative);
  return a;
}

PitchErrorAxis read_pitch_error(const JsonNode& n, int) {
  n.allow_only({"scale_um_per_m", "reference_mm", "periodic_amplitude_um", "periodic_period_mm",
                "periodic_phase_deg"},
               "parameter");
  PitchErrorAxis a;
  a.scale_um_per_m = optional(n, "scale_um_per_m", 0.0, any);
  a.reference_mm = optional(n, "reference_mm", 0.0, any);
  a.periodic_amplitude_um = optional(n, "periodic_amplitude_um", 0.0, non_negative);
  if (a.periodic_amplitude_um != 0.0 || n.has("periodic_period_mm"))
    a.periodic_period_mm = positive(n.child("periodic_period_mm"));
  a.periodic_phase_deg = optional(n, "periodic_phase_deg", 0.0, any);
  return a;
}

ThermalDriftAxis read_thermal_drift(const JsonNode& n, int) {
  n.allow_only({"gain_mm", "tau_s", "driver", "reference_power_kw"}, "parameter");
  ThermalDriftAxis a;
  a.gain_mm = n.child("gain_mm").number();
  a.tau_s = positive(n.child("tau_s"));
  if (n.has("driver")) {
    const JsonNode d = n.child("driver");
    const std::string s = d.string();
    if (s == "time")
      a.driver = ThermalDriver::Time;
    else if (s == "spindle_power")
      a.driver = ThermalDriver::SpindlePower;
    else
      d.fail("unknown driver '" + s + "'; known: time, spindle_power");
  }
  if (a.driver == ThermalDriver::SpindlePower || n.has("reference_power_kw"))
    a.reference_power_kw = positive(n.child("reference_power_kw"));
  return a;
}

GlobalEffect<SquarenessParams> read_squareness(const JsonNode& n) {
  n.allow_only({"enabled", "xy_urad", "yz_urad", "zx_urad"}, "key");
  GlobalEffect<SquarenessParams> e;
  e.enabled = n.child("enabled").boolean();
  e.params.xy_urad = optional(n, "xy_urad", 0.0, any);
  e.params.yz_urad = optional(n, "yz_urad", 0.0, any);
  e.params.zx_urad = optional(n, "zx_urad", 0.0, any);
  return e;
}

GlobalEffect<StraightnessParams> read_straightness(const JsonNode& n) {
  std::vector<std::string> known = {"enabled"};
  known.insert(known.end(), kStraightnessNames.begin(), kStraightnessNames.end());
  n.allow_only(known, "key");
  GlobalEffect<StraightnessParams> e;
  e.enabled = n.child("enabled").boolean();
  for (int i = 0; i < kStraightnessCount; ++i) {
    if (!n.has(kStraightnessNames[i])) continue;
    const JsonNode c = n.child(kStraightnessNames[i]);
    c.allow_only({"quadratic_um_per_m2", "cubic_um_per_m3", "reference_mm"}, "parameter");
    StraightnessComponent s;
    s.quadratic_um_per_m2 = optional(c, "quadratic_um_per_m2", 0.0, any);
    s.cubic_um_per_m3 = optional(c, "cubic_um_per_m3", 0.0, any);
    s.reference_mm = optional(c, "reference_mm", 0.0, any);
    e.params.components[i] = s;
  }
  return e;
}

Effects read_effects(const JsonNode& n) {
  n.allow_only({kEffectNames.begin(), kEffectNames.end()}, "effect");
  Effects e;
  if (n.has("servo_lag"))
    e.servo_lag = read_per_axis<ServoLagAxis>(n.child("servo_lag"), kJointCount, read_servo_lag);
  if (n.has("backlash"))
    e.backlash = read_per_axis<BacklashAxis>(n.child("backlash"), kJointCount, read_backlash);
  if (n.has("reversal_spike"))
    e.reversal_spike = read_per_axis<ReversalSpikeAxis>(n.child("reversal_spike"), kJointCount,
                                                        read_reversal_spike);
  if (n.has("pitch_error"))
    e.pitch_error = read_per_axis<PitchErrorAxis>(n.child("pitch_error"), 3, read_pitch_error);
  if (n.has("thermal_drift"))
    e.thermal_drift =
        read_per_axis<ThermalDriftAxis>(n.child("thermal_drift"), 3, read_thermal_drift);
  if (n.has("squareness")) e.squareness = read_squareness(n.child("squareness"));
  if (n.has("straightness")) e.straightness = read_straightness(n.child("straightness"));
  return e;
}

// Rules that join several parts of the file.
void check_consistency(const JsonNode& root, const MachineParams& m) {
  if (!root.has("effects")) return;
  const JsonNode fx = root.child("effects");
  auto axes_of = [&](const char* effect, auto const& e) {
    for (int j = 0; j < kJointCount; ++j) {
      if (!e.axes[j] || m.joints[j].present) continue;
      fx.child(effect)
          .child(std::string(kJointNames[j]))
          .fail("joint " + std::string(kJointNames[j]) + " is not listed in joints");
    }
  };
  axes_of("servo_lag", m.effects.servo_lag);
  axes_of("backlash", m.effects.backlash);
  axes_of("reversal_spike", m.effects.reversal_spike);
  for (int j = 0; j < kJointCount; ++j) {
    const auto& f = m.effects.reversal_spike.axes[j];
    if (!m.effects.reversal_spike.enabled || !f) continue;
    const std::string name(kJointNames[j]);
    const JsonNode n = fx.child("reversal_spike").child(name);
    if (!m.effects.servo_lag.active(j))
      n.fail("friction acts through the servo loop: switch on effects.servo_lag for " + name);
    // The explicit sub-step must stay stable: B/m · h < 1.
    const double per_s = servo_params(m, j).viscous_per_s;
    if (per_s * 25e-6 >= 0.5)
      n.child(detail::friction_keys(j)[1])
          .fail("too large for the joint's inertia (B/m = " + format_number(per_s) + " 1/s)");
  }
}

}  // namespace

DriveParams default_drive(int joint) {
  DriveParams d;
  if (joint_kind(joint) == JointKind::Rotary) {
    d.inertia = 2.0;
    d.max_accel = 20000.0;
  }
  return d;
}

MachineDescription parse_machine_description(const std::string& json_text,
                                             const std::string& file_name) {
  const nlohmann::json root_value = detail::parse_json_strict(json_text, file_name);
  const JsonNode root(file_name, root_value, "");
  root.allow_only({"truecut_machine", "name", "joints", "effects"}, "key");
  const JsonNode version = root.child("truecut_machine");
  if (version.integer() != 1)
    version.fail("unsupported version " + std::to_string(version.integer()) +
                 " (this build reads 1)");

  MachineDescription d;
  if (root.has("name")) d.name = root.child("name").string();
  const JsonNode joints = root.child("joints");
  joints.allow_only({kJointNames.begin(), kJointNames.end()}, "joint");
  for (int j = 0; j < kJointCount; ++j) {
    const std::string name(kJointNames[j]);
    if (joints.has(name) || joint_kind(j) == JointKind::Linear)
      d.machine.joints[j] = read_joint(joints.child(name), j);
    else
      d.machine.joints[j].drive = default_drive(j);
  }
  if (root.has("effects")) d.machine.effects = read_effects(root.child("effects"));
  check_consistency(root, d.machine);
  return d;
}

MachineDescription read_machine_description(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw MachineDescriptionError(file.string() + ": cannot read: " + std::strerror(errno));
  std::ostringstream ss;
  ss << in.rdbuf();
  return parse_machine_description(ss.str(), file.string());
}

}  // namespace truecut::sim
