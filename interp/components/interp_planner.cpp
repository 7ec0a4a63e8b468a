// interp_planner: runs a G-code program through the interpreter and planner
// at load time (non-real-time), feeds the plan to the servo thread through a
// lock-free channel and interpolates it every cycle.
//
//   loadrt interp_planner program=FILE.ngc [tool-table=FILE] [names=NAME]
//          [period-ns=1000000] [spline-tolerance=0.025] [rotary-weight=1]
//          [vmax=X,Y,Z,A,C] [amax=X,Y,Z,A,C] [jmax=X,Y,Z,A,C] [start=X,Y,Z,A,C]
//          [x-rot-point=0] [y-rot-point=0] [z-rot-point=0] [y-offset=0]
//          [z-offset=0] [tool-offset=0] [conventional-directions=0]
//          [max-blocks=50000000] [max-program-time=S]
//
// max-blocks bounds the blocks the interpreter executes (an endless loop);
// max-program-time (s, default none) refuses a program whose plan takes
// longer, naming the line where it passes the limit.
//
// Pins (docs/formats.md): out tcp-x/y/z (mm), axis-i/j/k, joint-x/y/z (mm),
// joint-a/c (deg), feed (mm/s), spindle-rpm (commanded, 0 when stopped),
// tool-length (mm, the G43 offset the kinematics use), line, tool, operation (s32), tcp-mode,
// done, underrun (bit); parameter (ro) program-time (s, the planned
// duration of the whole program, for progress reports). Function <name>.update; at the end of the
// program `done` goes true and the component asks the executor to stop.
#include <cmath>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "truecut/interp/error.hpp"
#include "truecut/interp/interpolator.hpp"
#include "truecut/interp/interpreter.hpp"
#include "truecut/interp/planner.hpp"
#include "truecut/rt/component_support.hpp"

namespace {

using namespace truecut;
using namespace truecut::interp;

struct Pins {
  double* tcp[3];
  double* axis[3];
  double* joint[5];
  double* feed;
  double* spindle_rpm;
  double* tool_length;
  int32_t* line;
  int32_t* tool;
  int32_t* operation;
  bool* tcp_mode;
  bool* done;
  bool* underrun;
};

struct Instance {
  Pins p{};
  Plan plan;
  size_t next = 0;  // next plan segment to push
  PlanChannel channel;
  Interpolator interpolator;
  const tc_hal_api_t* api = nullptr;
  tc_hal_t* hal = nullptr;
  bool stop_requested = false;
  double program_time_s = 0;
};

struct Module {
  std::vector<std::unique_ptr<Instance>> instances;
};

// Non-real-time: keeps the channel full.
void refill(void* arg) {
  auto& s = *static_cast<Instance*>(arg);
  while (s.next < s.plan.segments.size() && s.channel.try_push(s.plan.segments[s.next]))
    ++s.next;
}

void update(void* arg, long period_ns) {
  auto& s = *static_cast<Instance*>(arg);
  const CycleOutput& o = s.interpolator.step(s.channel, double(period_ns) * 1e-9);
  for (int i = 0; i < 3; ++i) {
    *s.p.tcp[i] = o.tcp_mm[i];
    *s.p.axis[i] = o.tool_axis[i];
  }
  for (int i = 0; i < 5; ++i)
    *s.p.joint[i] = o.joints[i];
  *s.p.feed = o.feed_mm_per_s;
  *s.p.spindle_rpm = o.spindle_rpm;
  *s.p.tool_length = o.tool_length_mm;
  *s.p.line = o.line;
  *s.p.tool = o.tool;
  *s.p.operation = o.operation;
  *s.p.tcp_mode = o.tcp_mode;
  *s.p.done = o.done;
  *s.p.underrun = o.underrun;
  if (o.done && !s.stop_requested) {
    s.stop_requested = true;
    s.api->request_stop(s.hal);
  }
}

std::vector<double> five(rt::hal::component::Args& args, const std::string& key,
                         bool positive = true) {
  auto v = args.take(key);
  if (!v) return {};
  std::vector<double> out;
  std::stringstream ss(*v);
  std::string item;
  while (std::getline(ss, item, ',')) {
    char* end = nullptr;
    const double d = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !std::isfinite(d) || (positive && !(d > 0)))
      throw rt::hal::component::InitError(key + "='" + *v + "': expected 5 " +
                                          (positive ? "positive " : "") + "numbers X,Y,Z,A,C");
    out.push_back(d);
  }
  if (out.size() != 5)
    throw rt::hal::component::InitError(key + "='" + *v + "': expected 5 numbers X,Y,Z,A,C");
  return out;
}

PlannerOptions planner_options(rt::hal::component::Args& args) {
  PlannerOptions o;
  o.servo_period_s = double(args.take_long("period-ns", 1'000'000, 1000, 1'000'000'000)) * 1e-9;
  o.spline_tolerance_mm = args.take_double("spline-tolerance", o.spline_tolerance_mm);
  o.rotary_weight_mm_per_deg = args.take_double("rotary-weight", o.rotary_weight_mm_per_deg);
  if (const auto start = five(args, "start", false); !start.empty())
    std::copy(start.begin(), start.end(), o.start_joints.begin());
  const auto vmax = five(args, "vmax"), amax = five(args, "amax"), jmax = five(args, "jmax");
  for (int i = 0; i < kAxisCount; ++i) {
    if (!vmax.empty()) o.limits.axis[i].max_velocity = vmax[i];
    if (!amax.empty()) o.limits.axis[i].max_acceleration = amax[i];
    if (!jmax.empty()) o.limits.axis[i].max_jerk = jmax[i];
  }
  rt::AcTrtParams& k = o.kinematics;
  k.x_rot_point_mm = args.take_double("x-rot-point", 0);
  k.y_rot_point_mm = args.take_double("y-rot-point", 0);
  k.z_rot_point_mm = args.take_double("z-rot-point", 0);
  k.y_offset_mm = args.take_double("y-offset", 0);
  k.z_offset_mm = args.take_double("z-offset", 0);
  k.tool_length_mm = args.take_double("tool-offset", 0);
  k.conventional_directions = args.take_long("conventional-directions", 0, 0, 1) != 0;
  return o;
}

// The first segment at which the plan's time passes max_s: refused there.
void check_program_time(const Plan& plan, const std::string& program, double max_s) {
  double t_s = 0;
  for (const PlanSegment& seg : plan.segments) {
    t_s += seg.law.duration_s;
    if (t_s <= max_s) continue;
    std::ostringstream m;
    m << program << ":" << seg.line << ": the planned program passes max-program-time=" << max_s
      << " s at this line (the whole program takes " << plan.stats.duration_s << " s)";
    throw rt::hal::component::InitError(m.str());
  }
}

}  // namespace

extern "C" TC_COMPONENT_EXPORT int truecut_component_init(const tc_hal_api_t* api, tc_hal_t* hal,
                                                          int argc, const char* const* argv,
                                                          void** module_state) {
  using namespace truecut::rt::hal::component;
  return init_guard(api, hal, [&] {
    Args args(argc, argv);
    auto program = args.take("program");
    if (!program) throw InitError("interp_planner needs program=FILE.ngc");
    InterpreterOptions iopt;
    if (auto table = args.take("tool-table")) iopt.tools = ToolTable::load(*table);
    // parameter-file=FILE.var (empty: none) parameter-units=mm|inch
    const std::string units = args.take_or("parameter-units", "mm");
    if (units != "mm" && units != "inch")
      throw InitError("parameter-units='" + units + "' must be mm or inch");
    const LengthUnits machine_units = units == "inch" ? LengthUnits::kInch : LengthUnits::kMm;
    // Without a file the units still say where the offset parameters keep
    // their lengths (the machine's units, as LinuxCNC's [TRAJ]LINEAR_UNITS).
    iopt.parameters.units = machine_units;
    if (auto file = args.take("parameter-file"); file && !file->empty())
      iopt.parameters = ParameterFile::load(*file, machine_units);
    const PlannerOptions popt = planner_options(args);
    iopt.max_blocks =
        args.take_long("max-blocks", static_cast<long>(iopt.max_blocks), 1, 1'000'000'000'000L);
    const double max_program_time_s = args.take_double("max-program-time", 0);
    if (!(max_program_time_s >= 0) || !std::isfinite(max_program_time_s))
      throw InitError("max-program-time=" + std::to_string(max_program_time_s) +
                      " must be a number of seconds >= 0 (0: no limit)");
    auto names = instance_names(args, "interp_planner", 1);
    args.expect_consumed("interp_planner");

    CanonProgram canon;
    try {
      canon = Interpreter(iopt).run_file(*program);
    } catch (const GcodeError& e) {
      throw InitError(e.what());
    }
    auto module = std::make_unique<Module>();
    for (const auto& n : names) {
      auto inst = std::make_unique<Instance>();
      inst->plan = plan_program(canon, popt);
      if (max_program_time_s > 0) check_program_time(inst->plan, *program, max_program_time_s);
      inst->api = api;
      inst->hal = hal;
      refill(inst.get());
      int id = new_component(api, hal, n);
      Builder b(api, hal, id);
      Pins& p = inst->p;
      const char* xyz[3] = {"x", "y", "z"};
      const char* ijk[3] = {"i", "j", "k"};
      const char* joints[5] = {"x", "y", "z", "a", "c"};
      for (int i = 0; i < 3; ++i) {
        b.pin(n + ".tcp-" + xyz[i], TC_HAL_FLOAT, TC_HAL_OUT, &p.tcp[i]);
        b.pin(n + ".axis-" + ijk[i], TC_HAL_FLOAT, TC_HAL_OUT, &p.axis[i]);
      }
      for (int i = 0; i < 5; ++i)
        b.pin(n + ".joint-" + joints[i], TC_HAL_FLOAT, TC_HAL_OUT, &p.joint[i]);
      b.pin(n + ".feed", TC_HAL_FLOAT, TC_HAL_OUT, &p.feed);
      b.pin(n + ".spindle-rpm", TC_HAL_FLOAT, TC_HAL_OUT, &p.spindle_rpm);
      b.pin(n + ".tool-length", TC_HAL_FLOAT, TC_HAL_OUT, &p.tool_length);
      b.pin(n + ".line", TC_HAL_S32, TC_HAL_OUT, &p.line);
      b.pin(n + ".tool", TC_HAL_S32, TC_HAL_OUT, &p.tool);
      b.pin(n + ".operation", TC_HAL_S32, TC_HAL_OUT, &p.operation);
      b.pin(n + ".tcp-mode", TC_HAL_BIT, TC_HAL_OUT, &p.tcp_mode);
      b.pin(n + ".done", TC_HAL_BIT, TC_HAL_OUT, &p.done);
      b.pin(n + ".underrun", TC_HAL_BIT, TC_HAL_OUT, &p.underrun);
      for (const PlanSegment& seg : inst->plan.segments)
        inst->program_time_s += seg.law.duration_s;
      b.param(n + ".program-time", TC_HAL_FLOAT, TC_HAL_RO, &inst->program_time_s);
      *p.axis[2] = 1.0;
      b.funct(n + ".update", update, inst.get());
      b.service(refill, inst.get());
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
