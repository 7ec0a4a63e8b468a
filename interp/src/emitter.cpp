#include "emitter.hpp"

namespace truecut::interp {

namespace {

// The calls LinuxCNC's interpreter queues behind held moves.
bool waits_behind_moves(const CanonOp& op) {
  return std::holds_alternative<SetFeedRate>(op) || std::holds_alternative<Dwell>(op) ||
         std::holds_alternative<SetFeedMode>(op) || std::holds_alternative<Coolant>(op) ||
         std::holds_alternative<StartSpindle>(op) || std::holds_alternative<StopSpindle>(op) ||
         std::holds_alternative<SetSpindleMode>(op) ||
         std::holds_alternative<SetSpindleSpeed>(op) || std::holds_alternative<Comment>(op);
}

}  // namespace

CanonCall Emitter::make(CanonOp op, double inverse_time_f) const {
  CanonCall call;
  call.context.file = file_;
  call.context.line = line_;
  call.context.block_number = block_number_;
  call.context.executed_block = executed_block_;
  call.context.outer_line = outer_line_;
  call.context.outer_loop_line = outer_loop_line_;
  call.context.operation = state_.operation;
  call.context.tool = state_.tool;
  call.context.units = state_.units;
  call.context.feed_mode = state_.feed_mode;
  call.context.incremental = state_.incremental;
  call.context.inverse_time_f = inverse_time_f;
  call.context.spline = state_.spline;
  call.context.tcp = state_.tcp;
  call.context.cutter_comp = state_.comp.active() && is_motion(op);
  if (state_.cycle.running != 0 && is_motion(op)) {
    call.context.canned_cycle = state_.cycle.running;
    call.context.cycle_plane = state_.plane;
    call.context.cycle_incremental = state_.incremental;
  }
  call.context.g5x_mm = state_.g5x_mm;
  call.context.g92_mm = state_.g92_mm;
  call.context.tool_offset_mm = state_.tool_offset_mm;
  call.context.xy_rotation_deg = state_.rotation_deg;
  call.op = std::move(op);
  return call;
}

void Emitter::deliver(CanonCall call) {
  if (sink_ != nullptr)
    (*sink_)(call, out_.files);
  else
    out_.calls.push_back(std::move(call));
}

void Emitter::emit(CanonOp op, double inverse_time_f) {
  if (!held_.empty() && waits_behind_moves(op)) {
    held_.push_back(HeldCall{make(std::move(op), inverse_time_f)});
    return;
  }
  deliver(make(std::move(op), inverse_time_f));
}

HeldCall& Emitter::hold(CanonOp op, double inverse_time_f) {
  held_.push_back(HeldCall{make(std::move(op), inverse_time_f)});
  return held_.back();
}

void Emitter::flush() {
  for (HeldCall& h : held_) {
    h.call.context.block_number = block_number_;
    deliver(std::move(h.call));
  }
  held_.clear();
}

}  // namespace truecut::interp
