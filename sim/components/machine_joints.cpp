// machine_joints: the simulated machine's five joints (x y z a c) with the
// physics effects of a machine description, as a HAL component.
//
//   loadrt machine_joints machine=FILE.json [count=N | names=a,b]
//
// FILE is read at load time (relative to the working folder); a bad file
// fails the load with "FILE: key.path: message". Per instance <i> and joint
// <j>:
//   in   <i>.<j>.pos-cmd         commanded joint position (mm, deg)
//   out  <i>.<j>.pos-act         encoder reading (motor side), at the command's instant
//   out  <i>.<j>.pos-true        table-side position along the joint (backlash, pitch, thermal)
//   out  <i>.<j>.vel-act         motor velocity (mm/s, deg/s)
//   out  <i>.<j>.f-error         pos-cmd − pos-act, the error the drive acts on
//   in   <i>.spindle-power-kw    drives thermal_drift with driver "spindle_power"
//   in   <i>.cut-force-x/-y/-z   cutting force on the tool (N, workpiece frame), from the
//                                cutting stage; drives tool_ and workpiece_deflection
//   in   <i>.cut-contact-x/-y/-z where it acts: the contact centroid (mm, workpiece frame)
//   out  <i>.true-x/-y/-z        linear slides incl. squareness and straightness (mm)
//   in   <i>.tool-length, <i>.tool-radius, <i>.tool-corner-radius
//                                the nominal tool in the spindle (mm; G43 length, tool
//                                table); unlinked they keep the description's tool
//   out  <i>.true-tcp-x/-y/-z    true TCP (tool tip) in the workpiece frame (mm), through the
//                                machine's true kinematics (rotary_location, tool_length_error)
//                                plus both deflections
//   out  <i>.true-tool-i/-j/-k   true tool axis in the workpiece frame (unit, TCP → spindle),
//                                tilted by tool_deflection
//   out  <i>.tool-deflection-x/-y/-z       tool tip shift by tool_deflection (mm)
//   out  <i>.workpiece-deflection-x/-y/-z  tool shift relative to the bent part (mm)
//   out  <i>.true-tool-length, <i>.true-tool-radius, <i>.true-tool-corner-radius
//                                the real cutter (mm): nominal tool + tool_*_error
//   out  <i>.fault               (bit, latched) a non-finite input was held
//   out  <i>.limit-fault         (bit, latched) a command left the joint's travel
// Function <i>.update. The model is sim/include/truecut/sim/machine_model.hpp.
#include <string>

#include "truecut/rt/component_support.hpp"
#include "truecut/sim/machine_model.hpp"

namespace {

using namespace truecut::sim;

struct JointPins {
  double* pos_cmd;
  double* pos_act;
  double* pos_true;
  double* vel_act;
  double* f_error;
};

struct Instance {
  MachineModel model;
  MachineState state;
  MachineInputs in;
  MachineOutputs out;
  JointPins joint[kJointCount];
  double* spindle_power_kw;
  double* tool_length;
  double* tool_radius;
  double* tool_corner_radius;
  double* cut_force[3];
  double* cut_contact[3];
  double* tool_deflection[3];
  double* workpiece_deflection[3];
  double* true_xyz[3];
  double* true_tcp[3];
  double* true_tool_axis[3];
  double* true_tool_length;
  double* true_tool_radius;
  double* true_tool_corner_radius;
  bool* fault;
  bool* limit_fault;
};

void update(void* arg, long period_ns) {
  auto& s = *static_cast<Instance*>(arg);
  for (int j = 0; j < kJointCount; ++j)
    s.in.pos_cmd[j] = *s.joint[j].pos_cmd;
  s.in.spindle_power_kw = *s.spindle_power_kw;
  s.in.tool_given = true;
  s.in.tool.length_mm = *s.tool_length;
  s.in.tool.radius_mm = *s.tool_radius;
  s.in.tool.corner_radius_mm = *s.tool_corner_radius;
  for (int i = 0; i < 3; ++i) {
    s.in.cut_force_n[i] = *s.cut_force[i];
    s.in.cut_contact_mm[i] = *s.cut_contact[i];
  }
  s.model.step(s.state, s.in, double(period_ns) * 1e-9, s.out);
  for (int j = 0; j < kJointCount; ++j) {
    *s.joint[j].pos_act = s.out.pos_act[j];
    *s.joint[j].pos_true = s.out.pos_true[j];
    *s.joint[j].vel_act = s.out.vel_act[j];
    *s.joint[j].f_error = s.out.f_error[j];
  }
  for (int i = 0; i < 3; ++i) {
    *s.true_xyz[i] = s.out.xyz_true[i];
    *s.true_tcp[i] = s.out.tcp_true[i];
    *s.true_tool_axis[i] = s.out.tool_axis_true[i];
    *s.tool_deflection[i] = s.out.tool_deflection_mm[i];
    *s.workpiece_deflection[i] = s.out.workpiece_deflection_mm[i];
  }
  const TrueTool& tool = s.out.tool_true;
  *s.true_tool_length = tool.length_mm;
  *s.true_tool_radius = tool.radius_mm;
  *s.true_tool_corner_radius = tool.corner_radius_mm;
  *s.fault = s.out.fault;
  *s.limit_fault = s.out.limit_fault;
}

}  // namespace

extern "C" TC_COMPONENT_EXPORT int truecut_component_init(const tc_hal_api_t* api, tc_hal_t* hal,
                                                          int argc, const char* const* argv,
                                                          void**) {
  using namespace truecut::rt::hal::component;
  return init_guard(api, hal, [&] {
    Args args(argc, argv);
    auto file = args.take("machine");
    auto names = instance_names(args, "machine_joints");
    args.expect_consumed("machine_joints");
    if (!file) throw InitError("machine_joints needs machine=FILE (a machine description JSON)");
    const MachineDescription description = read_machine_description(*file);
    for (const auto& n : names) {
      int id = new_component(api, hal, n);
      Builder b(api, hal, id);
      auto* s = b.alloc<Instance>();
      s->model = MachineModel(description.machine);
      for (int j = 0; j < kJointCount; ++j) {
        const std::string p = n + "." + std::string(kJointNames[j]) + ".";
        JointPins& jp = s->joint[j];
        b.pin(p + "pos-cmd", TC_HAL_FLOAT, TC_HAL_IN, &jp.pos_cmd);
        b.pin(p + "pos-act", TC_HAL_FLOAT, TC_HAL_OUT, &jp.pos_act);
        b.pin(p + "pos-true", TC_HAL_FLOAT, TC_HAL_OUT, &jp.pos_true);
        b.pin(p + "vel-act", TC_HAL_FLOAT, TC_HAL_OUT, &jp.vel_act);
        b.pin(p + "f-error", TC_HAL_FLOAT, TC_HAL_OUT, &jp.f_error);
      }
      b.pin(n + ".spindle-power-kw", TC_HAL_FLOAT, TC_HAL_IN, &s->spindle_power_kw);
      b.pin(n + ".tool-length", TC_HAL_FLOAT, TC_HAL_IN, &s->tool_length);
      b.pin(n + ".tool-radius", TC_HAL_FLOAT, TC_HAL_IN, &s->tool_radius);
      b.pin(n + ".tool-corner-radius", TC_HAL_FLOAT, TC_HAL_IN, &s->tool_corner_radius);
      const NominalTool& nominal = description.machine.kinematics.tool;
      *s->tool_length = nominal.length_mm;
      *s->tool_radius = nominal.radius_mm;
      *s->tool_corner_radius = nominal.corner_radius_mm;
      for (int i = 0; i < 3; ++i) {
        const std::string xyz(1, "xyz"[i]);
        b.pin(n + ".cut-force-" + xyz, TC_HAL_FLOAT, TC_HAL_IN, &s->cut_force[i]);
        b.pin(n + ".cut-contact-" + xyz, TC_HAL_FLOAT, TC_HAL_IN, &s->cut_contact[i]);
        b.pin(n + ".tool-deflection-" + xyz, TC_HAL_FLOAT, TC_HAL_OUT, &s->tool_deflection[i]);
        b.pin(n + ".workpiece-deflection-" + xyz, TC_HAL_FLOAT, TC_HAL_OUT,
              &s->workpiece_deflection[i]);
      }
      b.pin(n + ".true-x", TC_HAL_FLOAT, TC_HAL_OUT, &s->true_xyz[0]);
      b.pin(n + ".true-y", TC_HAL_FLOAT, TC_HAL_OUT, &s->true_xyz[1]);
      b.pin(n + ".true-z", TC_HAL_FLOAT, TC_HAL_OUT, &s->true_xyz[2]);
      for (int i = 0; i < 3; ++i) {
        b.pin(n + ".true-tcp-" + "xyz"[i], TC_HAL_FLOAT, TC_HAL_OUT, &s -> true_tcp[i]);
        b.pin(n + ".true-tool-" + "ijk"[i], TC_HAL_FLOAT, TC_HAL_OUT, &s -> true_tool_axis[i]);
      }
      b.pin(n + ".true-tool-length", TC_HAL_FLOAT, TC_HAL_OUT, &s->true_tool_length);
      b.pin(n + ".true-tool-radius", TC_HAL_FLOAT, TC_HAL_OUT, &s->true_tool_radius);
      b.pin(n + ".true-tool-corner-radius", TC_HAL_FLOAT, TC_HAL_OUT, &s->true_tool_corner_radius);
      b.pin(n + ".fault", TC_HAL_BIT, TC_HAL_OUT, &s->fault);
      b.pin(n + ".limit-fault", TC_HAL_BIT, TC_HAL_OUT, &s->limit_fault);
      b.funct(n + ".update", update, s);
      api->component_ready(hal, id);
    }
    return 0;
  });
}

extern "C" TC_COMPONENT_EXPORT void truecut_component_exit(const tc_hal_api_t*, tc_hal_t*, void*) {}
