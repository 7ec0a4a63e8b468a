// Reads the machine description JSON (docs/formats.md, "Machine description").
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

#include "json_node.hpp"
#include "machine_description_keys.hpp"
#include "truecut/rt/input_file.hpp"
#include "truecut/sim/machine_description.hpp"
#include "truecut/sim/machine_model.hpp"
#include "truecut/sim/true_tool_pose.hpp"

namespace truecut::sim {

using detail::format_number;
using detail::JsonNode;

namespace {

double in_range(const JsonNode& n, double lo, double hi) {
  const double v = n.number();
  if (!(v >= lo && v <= hi)) n.fail("must be in " + format_number(lo) + " .. " + format_number(hi));
  return v;
}

// Physical plausibility: a value outside these ranges is a unit mix-up or a
// typo, not a machine, and further on it turns tool-centre points into inf
// or NaN. Each range says why it is where it is.
struct Plausible {
  double lo, hi;
  const char* unit;
  const char* why;
};
constexpr Plausible kLength{-1e5, 1e5, "mm", "no machine is larger than 100 m"};
constexpr Plausible kTravelDeg{-1e7, 1e7, "deg",
                               "27,778 turns; give an endless axis a finite travel"};
constexpr Plausible kErrorUm{-1e4, 1e4, "um", "an error over 10 mm is a setup error"};
constexpr Plausible kAmplitudeUm{0.0, 1e4, "um", "an error over 10 mm is a setup error"};
constexpr Plausible kPositiveLength{1e-3, 1e5, "mm", "from 1 um to 100 m"};
constexpr Plausible kStickout{1e-3, 1000.0, "mm", "a tool longer than 1 m"};
constexpr Plausible kErrorMm{-10.0, 10.0, "mm", "an error over 10 mm is a setup error"};
constexpr Plausible kErrorUrad{-1e5, 1e5, "urad", "an angular error over 0.1 rad (5.7 deg)"};
constexpr Plausible kPhaseDeg{-3600.0, 3600.0, "deg", "ten turns"};
constexpr Plausible kScaleUmPerM{-1e4, 1e4, "um/m", "a scale error over 1 %"};
constexpr Plausible kStraightness{-1e3, 1e3, "um/m^n", "1 mm over 1 m"};
constexpr Plausible kPeriodMm{1e-3, 1e5, "mm", "a period from 1 um to 100 m"};
constexpr Plausible kTauS{1e-3, 1e6, "s", "a time constant from 1 ms to 11.6 days"};
constexpr Plausible kPowerKw{1e-3, 1e4, "kW", "a spindle from 1 W to 10 MW"};
constexpr Plausible kPlay{0.0, 10.0, "mm or deg", "a play over 10 mm or 10 deg"};
constexpr Plausible kFriction{0.0, 1e6, "N or N m (per mm/s or deg/s)", "1 MN of friction"};
constexpr Plausible kIntegralTimeS{1e-5, 100.0, "s", "an integral time from 10 us to 100 s"};
constexpr Plausible kInertia{1e-6, 1e6, "kg or kg m^2", "1000 t"};
constexpr Plausible kAccel{1e-3, 1e7, "mm/s^2 or deg/s^2", "1000 g"};
constexpr Plausible kEncoder{0.0, 1.0, "mm or deg", "a count of more than 1 mm or 1 deg"};
constexpr Plausible kStiffness{1e-6, 1e6, "N/um", "stiffer than any machine structure"};
constexpr Plausible kToolLength{0.0, 1000.0, "mm", "a tool longer than 1 m"};
constexpr Plausible kToolRadius{0.0, 500.0, "mm", "a tool over 1 m in diameter"};

double plausible(const JsonNode& n, const Plausible& r) {
  const double v = n.number();
  if (r.lo > 0.0 && !(v > 0.0)) n.fail("must be > 0");
  if (r.lo == 0.0 && !(v >= 0.0)) n.fail("must be >= 0");
  if (!(v >= r.lo && v <= r.hi))
    n.fail(format_number(v) + " is outside " + format_number(r.lo) + " .. " + format_number(r.hi) +
           " " + r.unit + " (" + r.why + "; check the unit)");
  return v;
}
auto within(const Plausible& r) {
  return [&r](const JsonNode& n) { return plausible(n, r); };
}
std::array<double, 3> plausible_vector3(const JsonNode& n, const Plausible& r) {
  const std::array<double, 3> v = n.vector3();
  for (int i = 0; i < 3; ++i)
    if (!(v[i] >= r.lo && v[i] <= r.hi))
      n.fail(std::string(1, "xyz"[i]) + " = " + format_number(v[i]) + " is outside " +
             format_number(r.lo) + " .. " + format_number(r.hi) + " " + r.unit + " (" + r.why +
             "; check the unit)");
  return v;
}

template <class F>
double optional(const JsonNode& obj, const std::string& key, double fallback, F&& read) {
  return obj.has(key) ? read(obj.child(key)) : fallback;
}

std::string unit(int joint) {
  return std::string(joint_unit(joint));
}

JointParams read_joint(const JsonNode& n, int j) {
  const std::string u = unit(j);
  n.allow_only({"min_" + u, "max_" + u, "drive"}, "key");
  JointParams p;
  p.present = true;
  const Plausible& travel = joint_kind(j) == JointKind::kLinear ? kLength : kTravelDeg;
  p.min = plausible(n.child("min_" + u), travel);
  p.max = plausible(n.child("max_" + u), travel);
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
    dp.vel_integral_time_s = optional(d, keys[1], dp.vel_integral_time_s, within(kIntegralTimeS));
    dp.inertia = optional(d, keys[2], dp.inertia, within(kInertia));
    dp.max_accel = optional(d, keys[3], dp.max_accel, within(kAccel));
    dp.encoder_resolution = optional(d, keys[4], dp.encoder_resolution, within(kEncoder));
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
  return {plausible(n.child("play_" + unit(j)), kPlay)};
}

ReversalSpikeAxis read_reversal_spike(const JsonNode& n, int j) {
  const auto keys = detail::friction_keys(j);
  n.allow_only({keys[0], keys[1]}, "parameter");
  ReversalSpikeAxis a;
  a.coulomb = plausible(n.child(keys[0]), kFriction);
  a.viscous = optional(n, keys[1], 0.0, within(kFriction));
  return a;
}

PitchErrorAxis read_pitch_error(const JsonNode& n, int) {
  n.allow_only({"scale_um_per_m", "reference_mm", "periodic_amplitude_um", "periodic_period_mm",
                "periodic_phase_deg"},
               "parameter");
  PitchErrorAxis a;
  a.scale_um_per_m = optional(n, "scale_um_per_m", 0.0, within(kScaleUmPerM));
  a.reference_mm = optional(n, "reference_mm", 0.0, within(kLength));
  a.periodic_amplitude_um = optional(n, "periodic_amplitude_um", 0.0, within(kAmplitudeUm));
  if (a.periodic_amplitude_um != 0.0 || n.has("periodic_period_mm"))
    a.periodic_period_mm = plausible(n.child("periodic_period_mm"), kPeriodMm);
  a.periodic_phase_deg = optional(n, "periodic_phase_deg", 0.0, within(kPhaseDeg));
  return a;
}

ThermalDriftAxis read_thermal_drift(const JsonNode& n, int) {
  n.allow_only({"gain_mm", "tau_s", "driver", "reference_power_kw"}, "parameter");
  ThermalDriftAxis a;
  a.gain_mm = plausible(n.child("gain_mm"), kErrorMm);
  a.tau_s = plausible(n.child("tau_s"), kTauS);
  if (n.has("driver")) {
    const JsonNode d = n.child("driver");
    const std::string s = d.string();
    if (s == "time")
      a.driver = ThermalDriver::kTime;
    else if (s == "spindle_power")
      a.driver = ThermalDriver::kSpindlePower;
    else
      d.fail("unknown driver '" + s + "'; known: time, spindle_power");
  }
  if (a.driver == ThermalDriver::kSpindlePower || n.has("reference_power_kw"))
    a.reference_power_kw = plausible(n.child("reference_power_kw"), kPowerKw);
  return a;
}

GlobalEffect<SquarenessParams> read_squareness(const JsonNode& n) {
  n.allow_only({"enabled", "xy_urad", "yz_urad", "zx_urad"}, "key");
  GlobalEffect<SquarenessParams> e;
  e.enabled = n.child("enabled").boolean();
  e.params.xy_urad = optional(n, "xy_urad", 0.0, within(kErrorUrad));
  e.params.yz_urad = optional(n, "yz_urad", 0.0, within(kErrorUrad));
  e.params.zx_urad = optional(n, "zx_urad", 0.0, within(kErrorUrad));
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
    s.quadratic_um_per_m2 = optional(c, "quadratic_um_per_m2", 0.0, within(kStraightness));
    s.cubic_um_per_m3 = optional(c, "cubic_um_per_m3", 0.0, within(kStraightness));
    s.reference_mm = optional(c, "reference_mm", 0.0, within(kLength));
    e.params.components[i] = s;
  }
  return e;
}

GlobalEffect<RotaryLocationParams> read_rotary_location(const JsonNode& n) {
  n.allow_only({"enabled", "a", "c"}, "key");
  GlobalEffect<RotaryLocationParams> e;
  e.enabled = n.child("enabled").boolean();
  if (n.has("a")) {
    const JsonNode a = n.child("a");
    a.allow_only({"e_y0a_um", "e_z0a_um", "e_b0a_urad", "e_c0a_urad", "e_a0a_urad"}, "parameter");
    RotaryLocationA& p = e.params.a;
    p.e_y0a_um = optional(a, "e_y0a_um", 0.0, within(kErrorUm));
    p.e_z0a_um = optional(a, "e_z0a_um", 0.0, within(kErrorUm));
    p.e_b0a_urad = optional(a, "e_b0a_urad", 0.0, within(kErrorUrad));
    p.e_c0a_urad = optional(a, "e_c0a_urad", 0.0, within(kErrorUrad));
    p.e_a0a_urad = optional(a, "e_a0a_urad", 0.0, within(kErrorUrad));
  }
  if (n.has("c")) {
    const JsonNode c = n.child("c");
    c.allow_only({"e_x0c_um", "e_y0c_um", "e_a0c_urad", "e_b0c_urad", "e_c0c_urad"}, "parameter");
    RotaryLocationC& p = e.params.c;
    p.e_x0c_um = optional(c, "e_x0c_um", 0.0, within(kErrorUm));
    p.e_y0c_um = optional(c, "e_y0c_um", 0.0, within(kErrorUm));
    p.e_a0c_urad = optional(c, "e_a0c_urad", 0.0, within(kErrorUrad));
    p.e_b0c_urad = optional(c, "e_b0c_urad", 0.0, within(kErrorUrad));
    p.e_c0c_urad = optional(c, "e_c0c_urad", 0.0, within(kErrorUrad));
  }
  return e;
}

GlobalEffect<ToolLengthErrorParams> read_tool_length_error(const JsonNode& n) {
  n.allow_only({"enabled", "length_mm"}, "key");
  GlobalEffect<ToolLengthErrorParams> e;
  e.enabled = n.child("enabled").boolean();
  e.params.length_mm = optional(n, "length_mm", 0.0, within(kErrorMm));
  return e;
}

GlobalEffect<ToolRadiusErrorParams> read_tool_radius_error(const JsonNode& n) {
  n.allow_only({"enabled", "radius_mm", "corner_radius_mm"}, "key");
  GlobalEffect<ToolRadiusErrorParams> e;
  e.enabled = n.child("enabled").boolean();
  e.params.radius_mm = optional(n, "radius_mm", 0.0, within(kErrorMm));
  e.params.corner_radius_mm = optional(n, "corner_radius_mm", 0.0, within(kErrorMm));
  return e;
}

GlobalEffect<ToolDeflectionParams> read_tool_deflection(const JsonNode& n) {
  n.allow_only({"enabled", "stiffness_n_per_um", "stickout_mm"}, "key");
  GlobalEffect<ToolDeflectionParams> e;
  e.enabled = n.child("enabled").boolean();
  e.params.stiffness_n_per_um = plausible(n.child("stiffness_n_per_um"), kStiffness);
  if (n.has("stickout_mm")) e.params.stickout_mm = plausible(n.child("stickout_mm"), kStickout);
  return e;
}

GlobalEffect<WorkpieceDeflectionParams> read_workpiece_deflection(const JsonNode& n) {
  n.allow_only({"enabled", "stiffness_n_per_um", "reference_length_mm", "clamp_point_mm", "axis"},
               "key");
  GlobalEffect<WorkpieceDeflectionParams> e;
  e.enabled = n.child("enabled").boolean();
  WorkpieceDeflectionParams& p = e.params;
  p.stiffness_n_per_um = plausible(n.child("stiffness_n_per_um"), kStiffness);
  p.reference_length_mm = plausible(n.child("reference_length_mm"), kPositiveLength);
  if (n.has("clamp_point_mm"))
    p.clamp_point_mm = plausible_vector3(n.child("clamp_point_mm"), kLength);
  if (n.has("axis")) {
    const JsonNode a = n.child("axis");
    p.axis = plausible_vector3(a, kLength);
    if (p.axis == std::array<double, 3>{}) a.fail("must not be [0, 0, 0]");
  }
  return e;
}

KinematicsParams read_kinematics(const JsonNode& n) {
  n.allow_only({"type", "x_rot_point_mm", "y_rot_point_mm", "z_rot_point_mm", "y_offset_mm",
                "z_offset_mm", "conventional_directions", "tool"},
               "key");
  KinematicsParams k;
  const JsonNode type = n.child("type");
  if (const std::string t = type.string(); t != "xyzac-trt")
    type.fail("unknown kinematics type '" + t + "'; known: xyzac-trt");
  k.type = KinematicsType::kXyzacTrt;
  k.ac.x_rot_point_mm = optional(n, "x_rot_point_mm", 0.0, within(kLength));
  k.ac.y_rot_point_mm = optional(n, "y_rot_point_mm", 0.0, within(kLength));
  k.ac.z_rot_point_mm = optional(n, "z_rot_point_mm", 0.0, within(kLength));
  k.ac.y_offset_mm = optional(n, "y_offset_mm", 0.0, within(kLength));
  k.ac.z_offset_mm = optional(n, "z_offset_mm", 0.0, within(kLength));
  if (n.has("conventional_directions"))
    k.ac.conventional_directions = n.child("conventional_directions").boolean();
  if (n.has("tool")) {
    const JsonNode t = n.child("tool");
    t.allow_only({"length_mm", "radius_mm", "corner_radius_mm"}, "parameter");
    k.tool.length_mm = optional(t, "length_mm", 0.0, within(kToolLength));
    k.tool.radius_mm = optional(t, "radius_mm", 0.0, within(kToolRadius));
    k.tool.corner_radius_mm = optional(t, "corner_radius_mm", 0.0, within(kToolRadius));
    if (k.tool.corner_radius_mm > k.tool.radius_mm)
      t.child("corner_radius_mm")
          .fail("must not exceed radius_mm (" + format_number(k.tool.radius_mm) + ")");
  }
  return k;
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
  if (n.has("rotary_location"))
    e.rotary_location = read_rotary_location(n.child("rotary_location"));
  if (n.has("tool_length_error"))
    e.tool_length_error = read_tool_length_error(n.child("tool_length_error"));
  if (n.has("tool_radius_error"))
    e.tool_radius_error = read_tool_radius_error(n.child("tool_radius_error"));
  if (n.has("tool_deflection"))
    e.tool_deflection = read_tool_deflection(n.child("tool_deflection"));
  if (n.has("workpiece_deflection"))
    e.workpiece_deflection = read_workpiece_deflection(n.child("workpiece_deflection"));
  return e;
}

// The real tool must still be a tool: radius >= 0, corner radius within it
// (checked whether the effect is on or off, as its parameters are kept).
void check_true_tool(const JsonNode& fx, const MachineParams& m) {
  if (!fx.has("tool_radius_error")) return;
  const JsonNode n = fx.child("tool_radius_error");
  const NominalTool& tool = m.kinematics.tool;
  const ToolRadiusErrorParams& e = m.effects.tool_radius_error.params;
  const bool ball = is_ball_end_mill(tool);
  const double radius = tool.radius_mm + e.radius_mm;
  const double corner = ball ? radius : tool.corner_radius_mm + e.corner_radius_mm;
  if (radius < 0.0)
    n.child("radius_mm")
        .fail("makes the true radius " + format_number(radius) +
              " negative (kinematics.tool.radius_mm is " + format_number(tool.radius_mm) + ")");
  if (ball && e.corner_radius_mm != 0.0)
    n.child("corner_radius_mm")
        .fail("must be 0: the nominal tool is a ball end mill, its corner follows radius_mm");
  if (!(corner >= 0.0 && corner <= radius))
    n.child(n.has("corner_radius_mm") ? "corner_radius_mm" : "radius_mm")
        .fail("makes the true corner radius " + format_number(corner) + " leave 0 .. " +
              format_number(radius) + " (the true radius)");
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
  if (fx.has("rotary_location")) {
    const JsonNode r = fx.child("rotary_location");
    for (const int j : {int(kA), int(kC)}) {
      const std::string name(kJointNames[j]);
      if (r.has(name) && !m.joints[j].present)
        r.child(name).fail("joint " + name + " is not listed in joints");
    }
  }
  check_true_tool(fx, m);
  // Without stickout_mm the tool's cantilever is the whole real tool: the
  // description's, or (kinematics.tool.length_mm = 0) the tool in the spindle
  // during the run (machine_joints' tool-length pin); a tool of length 0
  // does not bend.
}

}  // namespace

DriveParams default_drive(int joint) {
  DriveParams d;
  if (joint_kind(joint) == JointKind::kRotary) {
    d.inertia = 2.0;
    d.max_accel = 20000.0;
  }
  return d;
}

MachineDescription parse_machine_description(const std::string& json_text,
                                             const std::string& file_name) {
  const nlohmann::json root_value = detail::parse_json_strict(json_text, file_name);
  const JsonNode root(file_name, root_value, "");
  root.allow_only({"truecut_machine", "name", "joints", "kinematics", "effects"}, "key");
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
    if (joints.has(name) || joint_kind(j) == JointKind::kLinear)
      d.machine.joints[j] = read_joint(joints.child(name), j);
    else
      d.machine.joints[j].drive = default_drive(j);
  }
  if (root.has("kinematics")) d.machine.kinematics = read_kinematics(root.child("kinematics"));
  if (root.has("effects")) d.machine.effects = read_effects(root.child("effects"));
  check_consistency(root, d.machine);
  return d;
}

MachineDescription read_machine_description(const std::filesystem::path& file) {
  std::string text;
  try {
    text = rt::read_input_file(file, "machine description");
  } catch (const rt::InputFileError& e) {
    throw MachineDescriptionError(e.what());
  }
  return parse_machine_description(text, file.string());
}

}  // namespace truecut::sim
