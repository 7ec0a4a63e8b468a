// The cutting tool path of a program, as samples of the tool tip and tool
// axis in the workpiece frame, per tool (docs/offline.md, "Tool-centre
// placement"). Input: the canonical calls of truecut's interpreter.
//
// Conventions (docs/parts.md): the workpiece frame is the machine frame at
// A = C = 0, where the real-time component and the rewriter look the field
// up; a programmed point is placed in it as the controller places it, with
// the program's G5x origin, G92/G52 offsets and G10 L2 R rotation (all zero
// unless the program sets them). The programmed point is the tool tip (G43 active, or
// TRAORI, where X Y Z are the tip in the workpiece frame and A C set the tool
// axis (sin A sin C, sin A cos C, cos A)). Outside TRAORI the axis is +Z and
// the rotary axes must be at 0: with A or C turned the table carries the
// workpiece away from the program's frame, and without the machine's
// kinematics its position is unknown; such moves are counted, not sampled.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

#include "truecut/interp/canon.hpp"

namespace truecut::offline {

struct ToolPathSample {
  Eigen::Vector3d tip_mm = Eigen::Vector3d::Zero();  // programmed point in the workpiece frame
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();   // unit, from the tip towards the spindle
  double c_deg = 0.0;  // the C word under TRAORI (0 outside): at A = 0 the axis alone lacks it
  std::int32_t tool = 0;
  std::int32_t line = 0;        // program line of the move
  std::int32_t operation = -1;  // index into ToolPath::operations, -1 = none
};

struct ToolPathOptions {
  double step_mm = 0.1;            // largest tip distance between two samples
  double max_axis_step_deg = 0.5;  // largest change of A or C between two samples
  // BSPLINE/CSPLINE runs are sampled on the spline the planner builds, with
  // node insertion at this CAM tolerance.
  double spline_tolerance_mm = 0.025;
};

struct ToolPath {
  std::vector<ToolPathSample> samples;  // feed moves only (G1, G2/G3, splines), program order
  std::vector<std::string> operations;
  std::int64_t feed_moves = 0;
  std::int64_t rapid_moves = 0;
  // Feed moves outside TRAORI with A or C off zero (not sampled, see above).
  std::int64_t skipped_rotated_moves = 0;
  std::int32_t first_skipped_line = 0;
};

ToolPath sample_tool_path(const interp::CanonProgram& program, const ToolPathOptions& options = {});

}  // namespace truecut::offline
