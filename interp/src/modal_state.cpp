// M70 (save the modal state), M71 (forget it), M72 (restore it) and M73
// (save it and restore it when the subroutine returns) as LinuxCNC 2.9's
// rs274 runs them (docs/gcode.md, "Modal state: M70-M73").
#include <string>

#include "block_executor.hpp"

namespace truecut::interp {

namespace {

// LinuxCNC keeps the coolant as two M-code slots: M7 (mist on), M9 (both
// off) or none (flood only); and M8 (flood on) or none. A restore sets a
// slot only where the saved slot holds a code that differs.
int mist_slot(bool mist, bool flood) {
  return mist ? 70 : flood ? -1 : 90;
}
int flood_slot(bool flood) {
  return flood ? 80 : -1;
}

}  // namespace

BlockExecutor::ModalSnapshot BlockExecutor::snapshot() const {
  return {s_.units,
          s_.css,
          s_.feed_mode,
          s_.feed,
          s_.speed,
          s_.spindle,
          s_.mist,
          s_.flood,
          s_.plane,
          s_.tool_length_code,
          s_.coord_index,
          s_.path,
          s_.blend_tolerance,
          s_.naive_tolerance,
          s_.incremental,
          s_.arc_absolute,
          s_.retract_old_z};
}

void BlockExecutor::modal_state_codes() {
  const int code = codes_.m[static_cast<int>(MGroup::kSpindle)];
  if (code < 700 || code > 730) return;
  const int column = codes_.m_column[static_cast<int>(MGroup::kSpindle)];
  const int level = params_.call_level();
  if (static_cast<int>(saved_modal_.size()) <= level) saved_modal_.resize(level + 1);
  SavedModal& slot = saved_modal_[level];
  switch (code) {
    case 700:  // M70 keeps an M73's restore-on-return
      slot.state = snapshot();
      break;
    case 710:
      slot = SavedModal{};
      break;
    case 730:
      slot.state = snapshot();
      slot.autorestore = true;
      break;
    case 720: {
      if (!slot.state)
        fail(column,
             "M72 with no modal state saved at this call level (M70 or M73 first; M71 forgets "
             "it, and each subroutine call starts with none)");
      // LinuxCNC runs the restore as a block of its own and drops whatever
      // comes later on the line when there is something to restore: such
      // lines are refused rather than run two ways.
      bool later = !b_->g.empty() || b_->has_polar();
      for (char l : {'x', 'y', 'z', 'a', 'b', 'c'})
        later = later || b_->has(l);
      for (MGroup g : {MGroup::kCoolant, MGroup::kStop})
        later = later || codes_.m[static_cast<int>(g)] >= 0;
      if (later)
        fail(column,
             "M72 with G codes, axis words, coolant or stop codes on the same line: LinuxCNC "
             "drops them when it restores; put M72 on a line of its own");
      restore(*slot.state);
      break;
    }
    default:
      break;
  }
}

void BlockExecutor::return_from_call(int level) {
  if (level < static_cast<int>(saved_modal_.size())) {
    const SavedModal slot = saved_modal_[level];
    saved_modal_[level] = SavedModal{};
    if (slot.state && slot.autorestore) restore(*slot.state);
  }
}

void BlockExecutor::restore(const ModalSnapshot& saved) {
  // Units first, as a block of their own (they change what F means).
  if (saved.units != s_.units) set_units(saved.units);
  // The rest as one block of the codes that differ, compared before it
  // runs, in the order of execution.
  const ModalSnapshot now = snapshot();
  if (saved.css != now.css) {
    // rs274 does not save G96's D: a restored G96 has no limit.
    s_.css = saved.css;
    s_.css_max_rpm = saved.css ? kNoCssLimit : 0;
    out_.emit(SetSpindleMode{s_.css_max_rpm, s_.css});
  }
  if (saved.feed_mode != now.feed_mode) {
    s_.feed_mode = saved.feed_mode;
    if (saved.feed_mode == FeedMode::kInverseTime) {
      out_.emit(Comment{"interpreter: feed mode set to inverse time"});
      out_.emit(SetFeedMode{s_.feed_mode});
    } else {
      out_.emit(Comment{saved.feed_mode == FeedMode::kUnitsPerRevolution
                            ? "interpreter: feed mode set to units per revolution"
                            : "interpreter: feed mode set to units per minute"});
      out_.emit(SetFeedMode{s_.feed_mode});
      out_.emit(SetFeedRate{0});
    }
    s_.feed = 0;
  }
  if (saved.feed != now.feed && s_.feed_mode != FeedMode::kInverseTime) {
    s_.feed = saved.feed;
    out_.emit(SetFeedRate{s_.feed});
  }
  if (saved.speed != now.speed) {
    s_.speed = saved.speed;
    out_.emit(SetSpindleSpeed{s_.speed});
  }
  if (saved.spindle != now.spindle) {
    s_.spindle = saved.spindle;
    if (s_.spindle == 0)
      out_.emit(StopSpindle{});
    else
      out_.emit(StartSpindle{s_.spindle > 0});
  }
  const int mist = mist_slot(saved.mist, saved.flood);
  if (mist != -1 && mist != mist_slot(now.mist, now.flood)) {
    if (mist == 70) {
      s_.mist = true;
      out_.emit(Coolant{Coolant::kMist, true});
    } else {
      s_.mist = s_.flood = false;
      out_.emit(Coolant{Coolant::kMist, false});
      out_.emit(Coolant{Coolant::kFlood, false});
    }
  }
  const int flood = flood_slot(saved.flood);
  if (flood != -1 && flood != flood_slot(now.flood)) {
    s_.flood = true;
    out_.emit(Coolant{Coolant::kFlood, true});
  }
  if (saved.plane != now.plane) {
    s_.plane = saved.plane;
    out_.emit(SelectPlane{s_.plane});
  }
  if (saved.tool_length_code != now.tool_length_code) {
    s_.tool_length_code = saved.tool_length_code;
    // G49, or G43 without H: the tool in the spindle.
    Axes6 offset;
    if (saved.tool_length_code == 430 && s_.tool != 0)
      if (const ToolEntry* e = tools_.find(s_.tool)) offset = e->offset_mm;
    s_.tool_offset_mm = offset;
    out_.emit(UseToolLengthOffset{s_.to_program(offset)});
  }
  if (saved.coord_index != now.coord_index) select_coord_system(saved.coord_index);
  const bool path_differs =
      saved.path != now.path ||
      (saved.path == PathMode::kContinuous && (saved.blend_tolerance != now.blend_tolerance ||
                                               saved.naive_tolerance != now.naive_tolerance));
  if (path_differs) {
    s_.path = saved.path;
    if (saved.path == PathMode::kContinuous) {
      s_.blend_tolerance = saved.blend_tolerance;
      s_.naive_tolerance = saved.naive_tolerance;
      out_.emit(SetMotionControlMode{s_.path, s_.blend_tolerance});
      out_.emit(SetNaivecamTolerance{s_.naive_tolerance});
    } else {
      out_.emit(SetMotionControlMode{s_.path, 0});
    }
  }
  if (saved.incremental != now.incremental) {
    s_.incremental = saved.incremental;
    out_.emit(Comment{s_.incremental ? "interpreter: distance mode changed to incremental"
                                     : "interpreter: distance mode changed to absolute"});
  }
  if (saved.arc_absolute != now.arc_absolute) {
    s_.arc_absolute = saved.arc_absolute;
    out_.emit(Comment{s_.arc_absolute ? "interpreter: IJK distance mode changed to absolute"
                                      : "interpreter: IJK distance mode changed to incremental"});
  }
  if (saved.retract_old_z != now.retract_old_z) {
    s_.retract_old_z = saved.retract_old_z;
    out_.emit(Comment{s_.retract_old_z ? "interpreter: retract mode set to old_z"
                                       : "interpreter: retract mode set to r_plane"});
  }
}

}  // namespace truecut::interp
