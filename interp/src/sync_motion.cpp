// Spindle-synchronised motion G33 and rigid tapping G33.1 as LinuxCNC 2.9's
// interpreter makes them (docs/gcode.md, "Spindle-synchronised motion"):
// START_SPEED_FEED_SYNC(K), the move, STOP_SPEED_FEED_SYNCH.
#include <cmath>
#include <string>

#include "block_executor.hpp"

namespace truecut::interp {

void BlockExecutor::sync_motion(int code, const Axes6& target, int column, bool axis_words) {
  const std::string name = code == 330 ? "G33" : "G33.1";
  if (!b_->has('k')) fail(column, name + " needs K (the distance per spindle revolution)");
  if (b_->has('f'))
    fail(column_of('f'), "F word with " + name + ": the feed follows the spindle (K)");
  const double k = b_->value('k');
  // rs274 passes K <= 0 on; a pitch of zero or below cannot be cut.
  if (!(k > 0))
    fail(column_of('k'), "K (the distance per spindle revolution) must be greater than 0");
  if (!axis_words) fail(column, name + " needs an axis word (where to move)");
  if (s_.comp.side != 0) fail(column, name + " with cutter radius compensation on (G40 first)");
  if (s_.spindle == 0) fail(column, name + " needs the spindle turning (M3 or M4)");
  const Axes6 end = s_.program_position(target);
  if (code == 331) {
    // The tap comes back to where it started: XYZ only.
    for (char l : {'a', 'b', 'c'})
      if (b_->has(l))
        fail(column_of(l), std::string(1, static_cast<char>(l - 'a' + 'A')) +
                               " word with G33.1: rigid tapping moves X Y Z only");
  }
  out_.emit(SpeedFeedSync{true, k});
  if (code == 330) {
    out_.emit(StraightFeed{end});
    last_program_position_ = end;
    s_.position_mm = target;
  } else {
    out_.emit(RigidTap{end});
  }
  out_.emit(SpeedFeedSync{false, 0});
}

}  // namespace truecut::interp
