// The trajectory planner: canonical calls in, a time-parametrised plan out.
// Non-real-time (it allocates); deterministic (no clocks, no threads).
//
//   auto program = Interpreter(options).run_file("part.ngc");
//   Plan plan = plan_program(program, PlannerOptions{});
//   Interpolator ip;                      // the per-cycle side, see interpolator.hpp
//
// What it does, in order (docs/gcode.md, "Planner and interpolator"):
//  1. path: lines, arcs and helices in the planning space (joint space, or
//     (TCP, A, C) under TRAORI), BSPLINE/CSPLINE points turned into cubic
//     spans with node insertion;
//  2. blending: under G64 every corner between two lines is replaced by a
//     curvature-continuous cubic blend whose deviation is at most the G64 P
//     tolerance (without P: as large as half the shorter line allows); G61
//     keeps corners and G61.1 stops after every move;
//  3. limits: every piece gets a speed, acceleration and jerk bound along
//     its path parameter such that each joint stays within MachineLimits;
//     junctions get a speed cap from the change of the joints' first and
//     second derivatives there;
//  4. look-ahead: backward and forward passes give each junction the
//     highest speed the jerk-limited profile can reach and leave;
//  5. time law: one S-curve (7 phases of constant jerk, zero acceleration
//     at both ends) per segment.
#pragma once

#include <array>

#include <string>
#include <vector>

#include "truecut/interp/canon.hpp"
#include "truecut/interp/machine_limits.hpp"
#include "truecut/interp/plan_segment.hpp"
#include "truecut/interp/spline.hpp"
#include "truecut/rt/core/kinematics_ac.hpp"

namespace truecut::interp {

struct PlannerOptions {
  MachineLimits limits;
  // Machine kinematics; tool_length_mm is added to the active tool length
  // offset (G43) of each move.
  rt::AcTrtParams kinematics;
  double servo_period_s = 0.001;  // the period the plan is sampled at
  // Weight of the rotary axes in the planning space: 1 degree counts as this
  // many mm for blending tolerances and the planning metric.
  double rotary_weight_mm_per_deg = 1.0;
  // Under G64 without P: how far from the corner a blend may leave the lines
  // (mm of planning space); each line also gives at most half its length.
  double max_blend_length_mm = 10.0;
  // BSPLINE/CSPLINE node insertion tolerance (the source's CAM tolerance),
  // and the chord tolerance of G5/G5.1/G5.2 curves (nurbs_polyline).
  double spline_tolerance_mm = 0.025;
  bool spline_node_insertion = true;
  // Feed of G0 moves; 0 = as fast as the axis limits allow.
  double rapid_feed_mm_per_s = 0;
  // Where the machine stands when the program starts: joints x y z (mm),
  // a c (deg). Machine zero by default; a machine whose zero is inside the
  // part starts from a safe height instead.
  std::array<double, 5> start_joints{};
};

struct PlanStats {
  int moves = 0;          // programmed motion calls
  int blends = 0;         // corners replaced by a blend arc
  int exact_stops = 0;    // junctions planned at zero speed
  double duration_s = 0;  // total time of the plan
  double length_mm = 0;   // planning-space length
};

struct Plan {
  std::vector<PlanSegment> segments;
  std::vector<std::string> operations;  // PlanSegment::operation - 1 indexes this
  std::vector<SplineReport> splines;
  PlanStats stats;
};

// Throws std::invalid_argument for options that cannot be planned with
// (non-positive limits or period).
Plan plan_program(const CanonProgram& program, const PlannerOptions& options);

}  // namespace truecut::interp
