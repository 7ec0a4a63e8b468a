// Prints canonical calls in the layout LinuxCNC's standalone `rs274` uses,
// e.g. `STRAIGHT_FEED(1.0000, 2.0000, 3.0000, 0.0000, 0.0000, 0.0000)`, so
// the two interpreters can be compared line by line.
#pragma once

#include <string>

#include "truecut/interp/canon.hpp"

namespace truecut::interp {

struct FormatOptions {
  int decimals = 4;  // rs274 prints 4 (6 for the G64 tolerance)
};

// One call without line counter or newline. truecut's own calls print as
// SET_TCP(ON|OFF) and SET_SPLINE_MODE(NONE|BSPLINE|CSPLINE).
std::string format_rs274(const CanonOp& op, const FormatOptions& options = {});

}  // namespace truecut::interp
