// truecut_comp: applies the correction field to the tool-centre point every
// servo cycle. A shared-library HAL component:
//
//   loadrt truecut_comp [field=FILE.tcf] [mode=tcp|joint] [tools=T,T...]
//                       [count=N | names=A,B]
//
// Pins, fault codes and the hand-over protocol: docs/compensation.md. This
// file is the HAL edge only: it reads pins, calls rt::comp::step() (truecut/rt/comp.hpp)
// and writes pins; the field is loaded and freed by field_source.cpp in the
// component's background service (its own thread on the wall clock, so a
// large field never holds up the planner's refill).
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "field_source.hpp"
#include "truecut/rt/comp.hpp"
#include "truecut/rt/component_support.hpp"

namespace {

using namespace truecut;
using rt::comp::Fault;
using rt::comp::Vec3;

enum class Mode { kTcp, kJoint };

struct Pins {
  bool* enable;
  int32_t* tool;
  double* max_correction;  // mm
  double* max_rate;        // mm/s
  double* fade_time;       // s
  double* max_accel;       // mm/s^2
  double* max_jerk;        // mm/s^3
  double* max_tilt;        // rad: the tool-orientation correction's limits
  double* max_tilt_rate;   // rad/s
  double* max_tilt_accel;  // rad/s^2
  double* max_tilt_jerk;   // rad/s^3
  bool* reload;
  bool* swap_inhibit;
  bool* reset;
  std::array<double*, 3> tcp_in;  // tcp mode, mm
  std::array<double*, 3> axis_in;
  std::array<double*, 5> joint_in;  // joint mode: x y z (mm) a c (deg)
  std::array<double*, 5> joint_out;
  double* x_rot_point;  // joint mode kinematics, as xyzac-trt-kins
  double* y_rot_point;
  double* z_rot_point;
  double* y_offset;
  double* z_offset;
  double* tool_offset;
  bool* conventional_directions;
  double* a_min;  // deg
  double* a_max;
  std::array<double*, 3> joint_max_correction;  // joint mode, X Y Z, mm
  std::array<double*, 3> joint_min_limit;
  std::array<double*, 3> joint_max_limit;
  double* joint_a_max_correction;  // joint mode, A and C, deg (orientation correction)
  double* joint_c_max_correction;
  double* tilt_shortfall;  // joint mode, rad: the part of the tilt A and C cannot give
  int32_t* joint_clip_count;
  std::array<double*, 3> tcp_out;
  std::array<double*, 3> axis_out;
  std::array<double*, 3> corr;  // mm, workpiece frame
  double* corr_mag;
  std::array<double*, 3> tilt;  // rad, rotation vector, workpiece frame
  double* tilt_mag;
  bool* active;
  int32_t* fault;
  bool* limited;
  double* fade;
  int32_t* field_generation;
  int32_t* load_errors;
  int32_t* clamp_count;
  int32_t* fault_latched;
  uint32_t* expect_machine;  // ids a field must name (0: not checked)
  uint32_t* expect_part;
  uint32_t* expect_tool_set;
  uint32_t* field_crc_lo;  // CRC-64 of the current field's file, low and high 32 bits
  uint32_t* field_crc_hi;
  uint32_t* field_machine;  // ids the current field names
  uint32_t* field_part;
  uint32_t* field_tool_set;
};

struct Instance {
  Instance(std::string name_, Mode mode_, std::string path, std::vector<int32_t> tools)
      : name(std::move(name_)), mode(mode_), source(std::move(path), std::move(tools)) {}
  ~Instance() {
    const rt::CorrectionField* fields[] = {core.current.field, core.outgoing.field, pending};
    for (int i = 0; i < 3; ++i) {
      bool seen = false;
      for (int k = 0; k < i; ++k)
        seen = seen || fields[k] == fields[i];
      if (!seen) delete fields[i];
    }
    for (const rt::CorrectionField* f : backlog)
      delete f;
  }

  std::string name;
  Mode mode;
  Pins p{};
  rt::comp::CompState core;
  rt::comp::FieldSource source;
  const rt::CorrectionField* pending = nullptr;         // taken from the hand-over, not adopted yet
  std::array<const rt::CorrectionField*, 4> backlog{};  // retired while the queue was full
  bool reload_before = false;
  const tc_hal_api_t* api = nullptr;
  tc_hal_t* hal = nullptr;
};

struct Module {
  std::vector<std::unique_ptr<Instance>> instances;
};

Vec3 read3(const std::array<double*, 3>& pins) {
  return {*pins[0], *pins[1], *pins[2]};
}
void write3(const std::array<double*, 3>& pins, const Vec3& v) {
  for (int i = 0; i < 3; ++i)
    *pins[i] = v[i];
}

// Retires a field the core let go of; keeps it for later if the queue is full.
void retire(Instance& s, const rt::CorrectionField* field) noexcept {
  if (field == nullptr) return;
  if (s.source.handover().retire(field)) return;
  for (auto& slot : s.backlog)
    if (slot == nullptr) {
      slot = field;
      return;
    }
}

bool backlog_empty(Instance& s) noexcept {
  bool empty = true;
  for (auto& slot : s.backlog)
    if (slot != nullptr && !s.source.handover().retire(slot)) empty = false;
  return empty;
}

rt::AcTrtParams kinematics(const Pins& p) noexcept {
  rt::AcTrtParams k;
  k.x_rot_point_mm = *p.x_rot_point;
  k.y_rot_point_mm = *p.y_rot_point;
  k.z_rot_point_mm = *p.z_rot_point;
  k.y_offset_mm = *p.y_offset;
  k.z_offset_mm = *p.z_offset;
  k.tool_length_mm = *p.tool_offset;
  k.conventional_directions = *p.conventional_directions;
  k.a_min_deg = *p.a_min;
  k.a_max_deg = *p.a_max;
  return k;
}

rt::comp::JointLimits joint_limits(const Pins& p) noexcept {
  rt::comp::JointLimits l;
  for (int i = 0; i < 3; ++i) {
    l.max_correction[i] = *p.joint_max_correction[i];
    l.min_limit[i] = *p.joint_min_limit[i];
    l.max_limit[i] = *p.joint_max_limit[i];
  }
  l.max_a_correction_deg = *p.joint_a_max_correction;
  l.max_c_correction_deg = *p.joint_c_max_correction;
  return l;
}

void update(void* arg, long period_ns) {
  Instance& s = *static_cast<Instance*>(arg);
  const Pins& p = s.p;

  const bool reload = *p.reload;
  if (reload && !s.reload_before) s.source.request_reload();
  s.reload_before = reload;
  // A new field is offered to the core only when anything it might release
  // can be retired.
  const bool can_swap = backlog_empty(s);
  if (can_swap) s.source.handover().take_latest(s.pending);

  rt::comp::CycleInput in;
  in.enable = *p.enable;
  in.tool = *p.tool;
  in.candidate = can_swap ? s.pending : nullptr;
  in.swap_inhibit = *p.swap_inhibit;
  in.reset = *p.reset;
  in.expect_machine = *p.expect_machine;
  in.expect_part = *p.expect_part;
  in.expect_tool_set = *p.expect_tool_set;

  rt::AcTrtParams kins;
  rt::AcJoints joints;
  rt::comp::JointLimits jlim;
  rt::ToolPose pose;
  if (s.mode == Mode::kTcp) {
    pose.tcp_mm = read3(p.tcp_in);
    pose.axis = read3(p.axis_in);
    if (!pose.tcp_mm.allFinite() || !pose.axis.allFinite()) in.input_fault = Fault::kInputNotFinite;
  } else {
    kins = kinematics(p);
    joints = {*p.joint_in[0], *p.joint_in[1], *p.joint_in[2], *p.joint_in[3], *p.joint_in[4]};
    if (!rt::comp::joints_finite(joints) || !rt::comp::params_finite(kins)) {
      in.input_fault = Fault::kInputNotFinite;
    } else {
      pose = rt::forward_ac(kins, joints);
      jlim = joint_limits(p);
      in.joint_clip = rt::comp::joint_clip(kins, joints, pose, jlim);
      // Outside the A travel the inverse kinematics refuses; correct_joints()
      // still maps the correction while it fades out.
      if (!(joints.a_deg >= kins.a_min_deg && joints.a_deg <= kins.a_max_deg))
        in.input_fault = Fault::kKinematics;
    }
  }
  in.tcp_mm = pose.tcp_mm;

  const rt::comp::CompLimits limits{*p.max_correction, *p.max_rate,       *p.fade_time,
                                    *p.max_accel,      *p.max_jerk,       *p.max_tilt,
                                    *p.max_tilt_rate,  *p.max_tilt_accel, *p.max_tilt_jerk};
  const rt::comp::CycleOutput out = rt::comp::step(s.core, in, limits, double(period_ns) * 1e-9);
  if (out.adopted) {
    s.pending = nullptr;
    ++*p.field_generation;
  }
  retire(s, out.released);

  write3(p.corr, out.correction_mm);
  *p.corr_mag = out.correction_mm.norm();
  write3(p.tilt, out.rotation_rad);
  *p.tilt_mag = out.rotation_rad.norm();
  *p.active = out.active;
  *p.fault = static_cast<int32_t>(out.fault);
  *p.limited = out.limited;
  *p.fade = out.fade;
  *p.load_errors = s.source.load_errors();
  *p.clamp_count = s.core.clamp_count;
  *p.fault_latched = static_cast<int32_t>(out.latched);
  const rt::FieldIdentity id =
      s.core.current.field != nullptr ? s.core.current.field->identity() : rt::FieldIdentity{};
  *p.field_crc_lo = static_cast<uint32_t>(id.crc64);
  *p.field_crc_hi = static_cast<uint32_t>(id.crc64 >> 32);
  *p.field_machine = id.machine;
  *p.field_part = id.part;
  *p.field_tool_set = id.tool_set;
  // Position outputs hold their last value while the inputs are unusable.
  if (in.input_fault == Fault::kInputNotFinite) {
    if (s.mode == Mode::kJoint) *p.joint_clip_count = s.core.joint_clip_count;
    return;
  }
  write3(p.tcp_out, pose.tcp_mm + out.correction_mm);
  write3(p.axis_out, rt::comp::tilted_axis(pose.axis, out.rotation_rad));
  if (s.mode == Mode::kJoint) {
    // The tilt as far as small turns of A and C give it (joint_mode.hpp);
    // a turn cut by its bound counts as a joint clip.
    const rt::comp::RotaryCorrection rc =
        rt::comp::exactly_zero(out.rotation_rad)
            ? rt::comp::RotaryCorrection{}
            : rt::comp::rotary_correction(kins, joints, pose, out.rotation_rad, jlim);
    if (rc.clipped)
      s.core.joint_clip_count =
          static_cast<int32_t>(static_cast<uint32_t>(s.core.joint_clip_count) + 1u);
    *p.joint_clip_count = s.core.joint_clip_count;
    *p.tilt_shortfall = rc.shortfall_rad;
    rt::AcJoints j = rt::comp::correct_joints(kins, joints, pose, out.correction_mm, rc);
    if (in.joint_clip.active) rt::comp::clamp_joints(jlim, joints, j);
    const double v[5] = {j.x_mm, j.y_mm, j.z_mm, j.a_deg, j.c_deg};
    for (int i = 0; i < 5; ++i)
      *p.joint_out[i] = v[i];
  }
}

void service(void* arg) {
  Instance& s = *static_cast<Instance*>(arg);
  // No exception may cross the C ABI; FieldSource::service() only lets
  // allocation failures through.
  try {
    const std::string error = s.source.service();
    if (!error.empty())
      s.api->message(s.hal, TC_HAL_MSG_ERR, (s.name + ": reload failed: " + error).c_str());
  } catch (...) {
  }
}

std::vector<int32_t> parse_tools(const std::string& text) {
  std::vector<int32_t> tools;
  std::string cur;
  for (char c : text + ",") {
    if (c != ',') {
      cur += c;
      continue;
    }
    char* end = nullptr;
    const long t = std::strtol(cur.c_str(), &end, 10);
    if (cur.empty() || *end != '\0' || t < 0 || t > INT32_MAX)
      throw rt::hal::component::InitError("tools='" + text + "': '" + cur +
                                          "' is not a tool number");
    tools.push_back(static_cast<int32_t>(t));
    cur.clear();
  }
  return tools;
}

void make_pins(rt::hal::component::Builder& b, const std::string& n, Mode mode, Pins& p) {
  auto in_f = [&](const char* pin, double** ptr) {
    b.pin(n + "." + pin, TC_HAL_FLOAT, TC_HAL_IN, ptr);
  };
  auto out_f = [&](const char* pin, double** ptr) {
    b.pin(n + "." + pin, TC_HAL_FLOAT, TC_HAL_OUT, ptr);
  };
  b.pin(n + ".enable", TC_HAL_BIT, TC_HAL_IN, &p.enable);
  b.pin(n + ".tool", TC_HAL_S32, TC_HAL_IN, &p.tool);
  in_f("max-correction", &p.max_correction);
  in_f("max-rate", &p.max_rate);
  in_f("fade-time", &p.fade_time);
  in_f("max-accel", &p.max_accel);
  in_f("max-jerk", &p.max_jerk);
  in_f("max-tilt", &p.max_tilt);
  in_f("max-tilt-rate", &p.max_tilt_rate);
  in_f("max-tilt-accel", &p.max_tilt_accel);
  in_f("max-tilt-jerk", &p.max_tilt_jerk);
  b.pin(n + ".reload", TC_HAL_BIT, TC_HAL_IN, &p.reload);
  b.pin(n + ".swap-inhibit", TC_HAL_BIT, TC_HAL_IN, &p.swap_inhibit);
  b.pin(n + ".reset", TC_HAL_BIT, TC_HAL_IN, &p.reset);
  static const char* const kXyz[] = {"x", "y", "z"};
  static const char* const kIjk[] = {"i", "j", "k"};
  static const char* const kJoints[] = {"x", "y", "z", "a", "c"};
  if (mode == Mode::kTcp) {
    for (int i = 0; i < 3; ++i) {
      in_f((std::string("tcp-") + kXyz[i]).c_str(), &p.tcp_in[i]);
      in_f((std::string("axis-") + kIjk[i]).c_str(), &p.axis_in[i]);
    }
  } else {
    for (int i = 0; i < 5; ++i) {
      in_f((std::string("joint-") + kJoints[i]).c_str(), &p.joint_in[i]);
      out_f((std::string("joint-") + kJoints[i] + "-out").c_str(), &p.joint_out[i]);
    }
    in_f("x-rot-point", &p.x_rot_point);
    in_f("y-rot-point", &p.y_rot_point);
    in_f("z-rot-point", &p.z_rot_point);
    in_f("y-offset", &p.y_offset);
    in_f("z-offset", &p.z_offset);
    in_f("tool-offset", &p.tool_offset);
    b.pin(n + ".conventional-directions", TC_HAL_BIT, TC_HAL_IN, &p.conventional_directions);
    in_f("a-min", &p.a_min);
    in_f("a-max", &p.a_max);
    for (int i = 0; i < 3; ++i) {
      const std::string j = std::string("joint-") + kJoints[i];
      in_f((j + "-max-correction").c_str(), &p.joint_max_correction[i]);
      in_f((j + "-min-limit").c_str(), &p.joint_min_limit[i]);
      in_f((j + "-max-limit").c_str(), &p.joint_max_limit[i]);
    }
    in_f("joint-a-max-correction", &p.joint_a_max_correction);
    in_f("joint-c-max-correction", &p.joint_c_max_correction);
    out_f("tilt-shortfall", &p.tilt_shortfall);
    b.pin(n + ".joint-clip-count", TC_HAL_S32, TC_HAL_OUT, &p.joint_clip_count);
  }
  for (int i = 0; i < 3; ++i) {
    out_f((std::string("tcp-") + kXyz[i] + "-out").c_str(), &p.tcp_out[i]);
    out_f((std::string("axis-") + kIjk[i] + "-out").c_str(), &p.axis_out[i]);
    out_f((std::string("corr-") + kXyz[i]).c_str(), &p.corr[i]);
    out_f((std::string("tilt-") + kXyz[i]).c_str(), &p.tilt[i]);
  }
  out_f("corr-mag", &p.corr_mag);
  out_f("tilt-mag", &p.tilt_mag);
  b.pin(n + ".active", TC_HAL_BIT, TC_HAL_OUT, &p.active);
  b.pin(n + ".fault", TC_HAL_S32, TC_HAL_OUT, &p.fault);
  b.pin(n + ".limited", TC_HAL_BIT, TC_HAL_OUT, &p.limited);
  out_f("fade", &p.fade);
  b.pin(n + ".field-generation", TC_HAL_S32, TC_HAL_OUT, &p.field_generation);
  b.pin(n + ".load-errors", TC_HAL_S32, TC_HAL_OUT, &p.load_errors);
  b.pin(n + ".clamp-count", TC_HAL_S32, TC_HAL_OUT, &p.clamp_count);
  b.pin(n + ".fault-latched", TC_HAL_S32, TC_HAL_OUT, &p.fault_latched);
  b.pin(n + ".expect-machine-id", TC_HAL_U32, TC_HAL_IN, &p.expect_machine);
  b.pin(n + ".expect-part-id", TC_HAL_U32, TC_HAL_IN, &p.expect_part);
  b.pin(n + ".expect-tool-set-id", TC_HAL_U32, TC_HAL_IN, &p.expect_tool_set);
  b.pin(n + ".field-crc-lo", TC_HAL_U32, TC_HAL_OUT, &p.field_crc_lo);
  b.pin(n + ".field-crc-hi", TC_HAL_U32, TC_HAL_OUT, &p.field_crc_hi);
  b.pin(n + ".field-machine-id", TC_HAL_U32, TC_HAL_OUT, &p.field_machine);
  b.pin(n + ".field-part-id", TC_HAL_U32, TC_HAL_OUT, &p.field_part);
  b.pin(n + ".field-tool-set-id", TC_HAL_U32, TC_HAL_OUT, &p.field_tool_set);

  const rt::comp::CompLimits defaults;
  *p.max_correction = defaults.max_correction_mm;
  *p.max_rate = defaults.max_rate_mm_per_s;
  *p.fade_time = defaults.fade_time_s;
  *p.max_accel = rt::comp::kDefaultMaxAccelMmPerS2;
  *p.max_jerk = rt::comp::kDefaultMaxJerkMmPerS3;
  *p.max_tilt = defaults.max_tilt_rad;
  *p.max_tilt_rate = defaults.max_tilt_rate_rad_per_s;
  *p.max_tilt_accel = rt::comp::kDefaultMaxTiltAccelRadPerS2;
  *p.max_tilt_jerk = rt::comp::kDefaultMaxTiltJerkRadPerS3;
  if (mode == Mode::kTcp) {
    *p.axis_in[2] = 1.0;
  } else {
    *p.a_min = -180.0;
    *p.a_max = 180.0;
    const rt::comp::JointLimits jl;
    for (int i = 0; i < 3; ++i) {
      *p.joint_max_correction[i] = jl.max_correction[i];
      *p.joint_min_limit[i] = jl.min_limit[i];
      *p.joint_max_limit[i] = jl.max_limit[i];
    }
    *p.joint_a_max_correction = jl.max_a_correction_deg;
    *p.joint_c_max_correction = jl.max_c_correction_deg;
  }
  *p.axis_out[2] = 1.0;
}

}  // namespace

extern "C" TC_COMPONENT_EXPORT int truecut_component_init(const tc_hal_api_t* api, tc_hal_t* hal,
                                                          int argc, const char* const* argv,
                                                          void** module_state) {
  using namespace truecut::rt::hal::component;
  return init_guard(api, hal, [&] {
    Args args(argc, argv);
    const auto names = instance_names(args, "truecut_comp");
    const std::string path = args.take_or("field", "");
    const std::string mode_text = args.take_or("mode", "tcp");
    const std::string tools_text = args.take_or("tools", "");
    args.expect_consumed("truecut_comp");
    if (mode_text != "tcp" && mode_text != "joint")
      throw InitError("mode='" + mode_text + "' must be tcp or joint");
    const Mode mode = mode_text == "tcp" ? Mode::kTcp : Mode::kJoint;
    const std::vector<int32_t> tools =
        tools_text.empty() ? std::vector<int32_t>{} : parse_tools(tools_text);
    if (!tools.empty() && path.empty()) throw InitError("tools= needs field=");

    auto module = std::make_unique<Module>();
    for (const auto& n : names) {
      auto inst = std::make_unique<Instance>(n, mode, path, tools);
      inst->api = api;
      inst->hal = hal;
      // Every instance reads the file itself: instances never share a field.
      if (!path.empty()) inst->source.load_now();
      const int id = new_component(api, hal, n);
      Builder b(api, hal, id);
      make_pins(b, n, mode, inst->p);
      b.funct(n + ".update", update, inst.get());
      b.background_service(service, inst.get());
      api->component_ready(hal, id);
      module->instances.push_back(std::move(inst));
    }
    *module_state = module.release();
    return 0;
  });
}

extern "C" TC_COMPONENT_EXPORT void truecut_component_exit(const tc_hal_api_t*, tc_hal_t*,
                                                           void* module_state) {
  delete static_cast<Module*>(module_state);
}
