// Does a program stay inside a machine's travel? The program is planned
// with the machine's nominal kinematics (the path the interpolator will
// follow, blends included) and every motion segment is mapped to joints —
// joint-space lines at their ends (joints are linear along them), arcs,
// splines and TCP (TRAORI) moves at least every `max_step` of planning-space
// length and every 2° of arc. The first sample outside a joint's travel is
// reported with its program line:
//
//   program.ngc:123: joint z leaves travel [-50, 350] at 362.5 mm
//
// Non-real-time (plans, allocates); deterministic.
#pragma once

#include <array>
#include <optional>
#include <string>

#include "truecut/interp/canon.hpp"
#include "truecut/interp/planner.hpp"
#include "truecut/sim/joints.hpp"
#include "truecut/sim/machine_description.hpp"

namespace truecut::sim {

struct TravelExcursion {
  int line = 0;         // program line of the segment
  int joint = 0;        // JointIndex
  double position = 0;  // the joint's position there, mm or deg
  double min = 0, max = 0;
  std::string message;  // "FILE:LINE: joint J leaves travel [MIN, MAX] at POS UNIT"
};

struct ProgramTravel {
  // Extent of every joint over the sampled path (mm, deg); the start
  // position (machine zero) included.
  std::array<double, kJointCount> min{}, max{};
  std::optional<TravelExcursion> first_excursion;
  std::size_t samples = 0;
  bool inside() const { return !first_excursion; }
};

struct TravelCheckOptions {
  double max_step_mm = 0.5;  // sample spacing on curved or TCP segments (planning space)
  double max_arc_step_deg = 2.0;
};

// Samples the planned segments. The plan must have been made with the
// machine's kinematics (planner_options_for).
ProgramTravel program_travel(const interp::Plan& plan, const MachineParams& machine,
                             const std::string& program_name,
                             const TravelCheckOptions& options = {});

// Plans the interpreted program with planner_options_for(machine), then
// samples it. Throws interp::GcodeError when the program cannot be planned.
ProgramTravel program_travel(const interp::CanonProgram& program, const MachineParams& machine,
                             const std::string& program_name,
                             const TravelCheckOptions& options = {});

// Planner options for a machine: its nominal kinematics (nominal_ac_params:
// pivots, directions, the description's tool length — added to each G43
// offset — and the A travel); default limits otherwise.
interp::PlannerOptions planner_options_for(const MachineParams& machine);

}  // namespace truecut::sim
