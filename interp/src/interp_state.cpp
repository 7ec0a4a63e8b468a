#include "interp_state.hpp"

namespace truecut::interp {

Axes6 InterpState::to_program(const Axes6& mm) const {
  Axes6 out;
  for (int i = 0; i < 6; ++i)
    out[i] = to_program(i, mm[i]);
  return out;
}

Axes6 InterpState::program_position(const Axes6& machine) const {
  Axes6 out;
  for (int i = 0; i < 6; ++i)
    out[i] = to_program(i, machine[i] - g5x_mm[i] - g92_mm[i] - tool_offset_mm[i]);
  return out;
}

}  // namespace truecut::interp
