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
  if (rotation_deg != 0) {
    double x = machine.x - g5x_mm.x - tool_offset_mm.x, y = machine.y - g5x_mm.y - tool_offset_mm.y;
    rotate_xy_deg(x, y, -rotation_deg);
    out.x = to_program(0, x - g92_mm.x);
    out.y = to_program(1, y - g92_mm.y);
  }
  return out;
}

Axes6 InterpState::machine_position(const Axes6& program) const {
  Axes6 out;
  for (int i = 0; i < 6; ++i)
    out[i] = to_machine(i, program[i]) + g5x_mm[i] + g92_mm[i] + tool_offset_mm[i];
  if (rotation_deg != 0) {
    double x = to_machine(0, program.x) + g92_mm.x, y = to_machine(1, program.y) + g92_mm.y;
    rotate_xy_deg(x, y, rotation_deg);
    out.x = x + g5x_mm.x + tool_offset_mm.x;
    out.y = y + g5x_mm.y + tool_offset_mm.y;
  }
  return out;
}

}  // namespace truecut::interp
