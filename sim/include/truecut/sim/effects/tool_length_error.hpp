// tool_length_error: the real tool is longer (> 0) or shorter (< 0) than the
// length the program and the kinematics assume. The spindle carries the
// real tool, so the true TCP moves along the tool axis by the difference:
//
//   tcp_true = tcp − ΔL · axis        (axis points from the TCP to the spindle)
//
// at any A and C: a longer tool cuts deeper.
#pragma once

namespace truecut::sim {

struct ToolLengthErrorParams {
  double length_mm = 0.0;  // ΔL = real − nominal length
  bool operator==(const ToolLengthErrorParams&) const = default;
};

}  // namespace truecut::sim
