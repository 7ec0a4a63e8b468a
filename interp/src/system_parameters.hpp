// The parameters LinuxCNC keeps for the machine state: coordinate systems
// (#5221.. in steps of 20), G92 (#5211..), G28/G30 homes (#5161.., #5181..),
// the current position (#5420..), tool (#5400..), and the read-only
// predefined names (#<_x>, #<_metric>, ...).
#pragma once

#include <optional>
#include <string_view>

#include "interp_state.hpp"
#include "parameters.hpp"

namespace truecut::interp {

constexpr int kG28Home = 5161;
constexpr int kG30Home = 5181;
constexpr int kG92Enabled = 5210;
constexpr int kG92Offsets = 5211;
constexpr int kCoordSystemIndex = 5220;
constexpr int kLoadedToolOffsets = 5401;  // #5401..#5413: the loaded tool's row
constexpr int kDebugSwitch = 5599;        // (DEBUG,...) messages shown when non-zero
// First parameter of coordinate system n (1 = G54 .. 9 = G59.3).
constexpr int coord_system_base(int n) {
  return 5201 + 20 * n;
}
// The XY rotation (degrees, G10 L2 R) of a system: coord_system_base + 9
// (#5230 for G54, #5250 for G55, ...).
constexpr int kCoordSystemRotation = 9;

// Writes the read-only state parameters (#5220, #5400.., #5420..).
void sync_state_parameters(const InterpState& state, Parameters& params);
// #<_x>, #<_metric>, ...; nullopt for names that are not predefined.
std::optional<double> predefined_parameter(const InterpState& state, const Parameters& params,
                                           std::string_view name);

}  // namespace truecut::interp
