// The machine each benchmark part is machined on: one mid-size 5-axis A/C
// table-table mill, with the part's hidden physics switched on. The
// magnitudes and why they are realistic: docs/parts.md, "Machines".
#include <string>

#include "truecut/sim/benchmark_parts.hpp"

namespace truecut::sim {
namespace {

JointParams joint(double min, double max, DriveParams drive) {
  JointParams j;
  j.present = true;
  j.min = min;
  j.max = max;
  j.drive = drive;
  return j;
}

// Joint coordinates are relative to the workpiece origin: the workpiece
// frame coincides with the machine frame at A = C = 0 (docs/kinematics.md).
MachineParams base_machine() {
  MachineParams m;
  // Travel: X 500, Y 450, Z 400 mm, trunnion A −10…110°, C endless (±100 turns).
  m.joints[kX] = joint(-250, 250, {40.0, 0.010, 450.0, 4000.0, 0.0001});
  m.joints[kY] = joint(-225, 225, {40.0, 0.010, 600.0, 3500.0, 0.0001});
  m.joints[kZ] = joint(-50, 350, {50.0, 0.008, 300.0, 4000.0, 0.0001});
  m.joints[kA] = joint(-10, 110, {30.0, 0.012, 4.0, 8000.0, 0.0001});
  m.joints[kC] = joint(-36000, 36000, {40.0, 0.010, 1.5, 12000.0, 0.0001});
  // The C axis passes through the workpiece origin (the part is centred on
  // the table); the A axis lies 100 mm below it.
  m.kinematics.ac.x_rot_point_mm = 0;
  m.kinematics.ac.y_rot_point_mm = 0;
  m.kinematics.ac.z_rot_point_mm = -100;
  m.kinematics.ac.y_offset_mm = 0;
  m.kinematics.ac.z_offset_mm = 0;
  m.kinematics.ac.conventional_directions = false;
  return m;
}

// The tool whose radius error the part hides: the finishing tool of the
// surfaces the CMM judges first. Its length stays 0: the programs apply the
// lengths of tools.tbl with G43, and the planner adds this length on top.
NominalTool judged_tool(const BenchmarkPart& part) {
  const int number = part.id == PartId::kImplant ? 1 : part.id == PartId::kBenchmark004 ? 2 : 1;
  NominalTool t;
  for (const PartTool& pt : part.metadata.tools) {
    if (pt.number != number) continue;
    t.radius_mm = pt.radius_mm;
    t.corner_radius_mm = pt.corner_radius_mm;
  }
  return t;
}

std::string machine_name(const BenchmarkPart& part, bool ideal) {
  return "truecut 5-axis A/C table-table mill for " + part.metadata.name +
         (ideal ? " (ideal: every effect off)" : " (hidden physics of the demo)");
}

}  // namespace

MachineDescription part_machine_ideal(const BenchmarkPart& part) {
  MachineDescription d;
  d.name = machine_name(part, true);
  d.machine = base_machine();
  d.machine.kinematics.tool = judged_tool(part);
  return d;
}

MachineDescription part_machine(const BenchmarkPart& part) {
  MachineDescription d = part_machine_ideal(part);
  d.name = machine_name(part, false);
  Effects& e = d.machine.effects;

  // Position loops tuned a little apart: Kv 25…33 1/s, feed-forward 0.90…0.95.
  e.servo_lag.enabled = true;
  e.servo_lag.axes[kX] = ServoLagAxis{30.0, 0.95};
  e.servo_lag.axes[kY] = ServoLagAxis{28.0, 0.93};
  e.servo_lag.axes[kZ] = ServoLagAxis{33.3, 0.95};
  e.servo_lag.axes[kA] = ServoLagAxis{25.0, 0.90};
  e.servo_lag.axes[kC] = ServoLagAxis{25.0, 0.90};

  // The real cutter is smaller than the one CAM was told about.
  e.tool_radius_error.enabled = true;
  switch (part.id) {
    case PartId::kImplant:
      e.tool_radius_error.params.radius_mm = -0.02;  // Ø2 end mill at the h10 limit
      break;
    case PartId::kBenchmark004:
      e.tool_radius_error.params.radius_mm = -0.1;  // the model-adaptation source's error
      break;
    case PartId::kFreeform:
      e.tool_radius_error.params.radius_mm = -0.05;
      break;
  }

  if (part.id == PartId::kImplant) {
    // The presetter measured the tools 15 µm long: the real tools are
    // shorter than tools.tbl says, so the face milled with the tool's end
    // stands 15 µm high (the face of the optical-compensation source).
    e.tool_length_error.enabled = true;
    e.tool_length_error.params.length_mm = -0.015;
  }

  if (part.id == PartId::kFreeform) {
    // ISO 230-7 location errors of a calibrated trunnion: 5…10 µm, 8…25 µrad.
    e.rotary_location.enabled = true;
    e.rotary_location.params.a = RotaryLocationA{8.0, -5.0, 0.0, 15.0, 20.0};
    e.rotary_location.params.c = RotaryLocationC{10.0, -6.0, 12.0, -8.0, 25.0};
  }

  // Cutting forces bend the tool and, on the implant, the slender shaft.
  // Beam theory k = 3EI/L³ with holder and spindle in series (docs/parts.md,
  // "Machines"); the stiffness is the judged tool's, the stick-out follows
  // the length of the tool in the spindle.
  e.tool_deflection.enabled = true;
  e.tool_deflection.params.stiffness_n_per_um = part.id == PartId::kImplant ? 0.054 : 1.6;
  if (part.id == PartId::kImplant) {
    e.workpiece_deflection.enabled = true;
    e.workpiece_deflection.params.stiffness_n_per_um = 0.038;
    e.workpiece_deflection.params.reference_length_mm = 17.0;
    e.workpiece_deflection.params.clamp_point_mm = {0.0, 0.0, 0.0};
    e.workpiece_deflection.params.axis = {0.0, 0.0, 1.0};
  }
  return d;
}

}  // namespace truecut::sim
