// The parameters surface mode fits and how each nudges the machine
// description. Deflections are fitted as compliances 1/k (µm/N), in which
// the surface deviation is close to linear, and reported as stiffness.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "truecut/sim/machine_description.hpp"

namespace truecut::analysis::diagnosis {

struct SurfaceParam {
  std::string effect;
  std::string axis;         // squareness plane; empty otherwise
  std::string key;          // description key ("a.e_y0a_um": in the effect's "a" object)
  double step = 0;          // finite-difference nudge, fitted unit
  double base = 0;          // believed value, fitted unit
  bool compliance = false;  // fitted as 1/key
};

// Where a workpiece_deflection the believed model lacks is clamped: at the
// bottom of the nominal, along +Z, its height as the reference length.
struct WorkpieceGeometry {
  std::array<double, 3> clamp_point_mm{};
  double reference_length_mm = 10.0;
};

std::vector<SurfaceParam> surface_params(const sim::MachineParams& believed, bool five_axis);
// Sets the parameter to `value` (fitted unit), switching its effect on
// (a deflection with compliance <= 0 is switched off).
void set_surface_param(sim::MachineParams& m, const SurfaceParam& p, double value,
                       const WorkpieceGeometry& geometry);
// "effect" or "effect:plane": the unit of selection.
std::string surface_group(const SurfaceParam& p);

}  // namespace truecut::analysis::diagnosis
