// G10 L1, L10 and L11: tool table edits during the program, as LinuxCNC
// 2.9's rs274 makes them (docs/gcode.md "Tool table edits G10 L1/L10/L11").
#include <cmath>

#include "block_executor.hpp"
#include "system_parameters.hpp"
#include "truecut/rt/number_format.hpp"

namespace truecut::interp {

namespace {

constexpr char kAxisLetters[6] = {'x', 'y', 'z', 'a', 'b', 'c'};
constexpr int kG593 = 9;  // G59.3: L11's fixture

}  // namespace

void BlockExecutor::tool_table_edit(int l) {
  const int col = codes_.g_column[0];
  const std::string name = "G10 L" + std::to_string(l);
  if (!b_->has('p')) fail(col, name + " needs P (the tool number)");
  const double pv = b_->value('p');
  if (pv < 1 || pv != std::floor(pv))
    fail(column_of('p'), name + " P (the tool number) must be a whole number >= 1");
  if (pv > kLargestWholeWord)
    fail(column_of('p'), "tool " + rt::format_shortest(pv) + " is not in the tool table");
  const int tool = static_cast<int>(pv);
  ToolEntry* e = tools_.find(tool);
  if (!e) fail(column_of('p'), "tool " + std::to_string(tool) + " is not in the tool table");
  if (b_->has('q')) {
    const double q = b_->value('q');
    if (q < 0 || q > 9 || q != std::floor(q))
      fail(column_of('q'), name + " Q (the tool orientation) must be a whole number 0..9");
  }
  if (b_->has('r') && !std::isfinite(2 * b_->value('r')))
    fail(column_of('r'), name + " R: the diameter is not a finite number");
  // L10: the offset that puts the tool, with it applied, at the word in the
  // active system (G5x and G92/G52 applied). L11: the same with G59.3's
  // origin instead and no G92/G52 offset.
  const Axes6 prog = s_.program_position();
  Axes6 fixture;
  for (int i = 0; i < 6; ++i)
    fixture[i] = s_.to_program(i, s_.from_param(i, params_.get(coord_system_base(kG593) + i)));
  const bool rotated = s_.rotation_deg != 0;
  const Axes6 old_offset_mm = e->offset_mm;
  for (int i = 0; i < 6; ++i) {
    const char letter = kAxisLetters[i];
    if (!b_->has(letter)) continue;
    const double v = b_->value(letter);
    double offset = v;  // L1: the word itself
    if (l == 10) offset = prog[i] + s_.to_program(i, s_.tool_offset_mm[i]) - v;
    if (l == 11)
      offset = (rotated ? s_.to_program(i, s_.position_mm[i])
                        : prog[i] + s_.to_program(
                                        i, s_.g5x_mm[i] + s_.g92_mm[i] + s_.tool_offset_mm[i])) -
               fixture[i] - v;
    e->offset_mm[i] = s_.to_machine(i, offset);
  }
  if (l == 10 && rotated && (b_->has('x') || b_->has('y'))) {
    // Under an XY rotation rs274 works in the rotated frame: the entry's X
    // and Y turned into it, the given words' components replaced by the
    // offset that puts the tool at them, the result turned back. A missing
    // word keeps the entry's component in that frame, not the position's.
    double px = s_.position_mm.x - s_.g5x_mm.x, py = s_.position_mm.y - s_.g5x_mm.y;
    rotate_xy_deg(px, py, -s_.rotation_deg);
    double tx = old_offset_mm.x, ty = old_offset_mm.y;
    rotate_xy_deg(tx, ty, -s_.rotation_deg);
    if (b_->has('x')) tx = px - s_.to_machine(0, b_->value('x')) - s_.g92_mm.x;
    if (b_->has('y')) ty = py - s_.to_machine(1, b_->value('y')) - s_.g92_mm.y;
    rotate_xy_deg(tx, ty, s_.rotation_deg);
    e->offset_mm.x = tx;
    e->offset_mm.y = ty;
  }
  if (b_->has('r')) e->diameter_mm = s_.to_machine(0, 2 * b_->value('r'));
  if (b_->has('i')) e->front_angle_deg = b_->value('i');
  if (b_->has('j')) e->back_angle_deg = b_->value('j');
  if (b_->has('q')) e->orientation = static_cast<int>(b_->value('q'));
  axes_used_ = true;
  SetToolTableEntry entry;
  entry.pocket = tools_.slot_of(tool).value_or(0);
  entry.tool = tool;
  entry.offset = s_.to_program(e->offset_mm);
  entry.diameter = s_.to_program(0, e->diameter_mm);
  entry.front_angle_deg = e->front_angle_deg;
  entry.back_angle_deg = e->back_angle_deg;
  entry.orientation = e->orientation;
  out_.emit(entry);
  if (entry.pocket == s_.spindle_slot) {  // the spindle's copy too, as rs274
    entry.pocket = 0;
    out_.emit(entry);
    loaded_tool_parameters();
  }
}

// rs274 shows the loaded tool's row in #5401..#5413 (X Y Z A B C U V W
// offsets, diameter, front and back angle, orientation) in the machine's
// units, the tool table's: written by M6 and by a G10 L1/L10/L11 that edits
// the loaded tool (not by M61, nor by M6 of T0, as LinuxCNC 2.9).
void BlockExecutor::loaded_tool_parameters() {
  const ToolEntry* e = tools_.find(s_.tool);
  if (!e) return;
  const double per_mm = tools_.units() == LengthUnits::kInch ? 1.0 / kMmPerInch : 1.0;
  for (int i = 0; i < 6; ++i)
    params_.set(kLoadedToolOffsets + i, i < 3 ? e->offset_mm[i] * per_mm : e->offset_mm[i]);
  for (int i = 6; i < 9; ++i)  // U V W: no such axes
    params_.set(kLoadedToolOffsets + i, 0.0);
  params_.set(kLoadedToolOffsets + 9, e->diameter_mm * per_mm);
  params_.set(kLoadedToolOffsets + 10, e->front_angle_deg);
  params_.set(kLoadedToolOffsets + 11, e->back_angle_deg);
  params_.set(kLoadedToolOffsets + 12, e->orientation);
}

}  // namespace truecut::interp
