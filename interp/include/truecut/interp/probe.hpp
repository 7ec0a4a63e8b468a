// What the machine (or the simulator) reports after a probing move G38.2-
// G38.5: the interpreter asks through InterpreterOptions::probe and sets the
// parameters #5061-#5070 and its position from the answer, as LinuxCNC's
// interpreter does from its canon layer (docs/gcode.md, "Probing").
#pragma once

#include <functional>

#include "truecut/interp/canon.hpp"

namespace truecut::interp {

// Machine positions in mm (degrees for A B C): G5x, G92 and tool length
// offsets applied.
struct ProbeRequest {
  Axes6 start_mm;
  Axes6 target_mm;
  int kind = 2;  // G38.kind: 2 3 toward the work (trip on contact), 4 5 away
};

struct ProbeResult {
  bool tripped = false;
  Axes6 trip_mm;  // where the probe tripped (the target when it did not)
  Axes6 end_mm;   // where the machine stopped
};

using ProbeFunction = std::function<ProbeResult(const ProbeRequest&)>;

// LinuxCNC's standalone rs274 (no machine): the probe never trips, the trip
// point is the target, and the machine ends 0.254 mm (0.01 in) short of it,
// back toward the start along the XYZ motion.
ProbeResult standalone_probe(const ProbeRequest& request);

}  // namespace truecut::interp
