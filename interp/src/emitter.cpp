#include "emitter.hpp"

namespace truecut::interp {

void Emitter::emit(CanonOp op, double inverse_time_f) {
  CanonCall call;
  call.context.file = file_;
  call.context.line = line_;
  call.context.block_number = block_number_;
  call.context.operation = state_.operation;
  call.context.tool = state_.tool;
  call.context.units = state_.units;
  call.context.feed_mode = state_.feed_mode;
  call.context.inverse_time_f = inverse_time_f;
  call.context.spline = state_.spline;
  call.context.tcp = state_.tcp;
  call.context.g5x_mm = state_.g5x_mm;
  call.context.g92_mm = state_.g92_mm;
  call.context.tool_offset_mm = state_.tool_offset_mm;
  call.op = std::move(op);
  if (sink_ != nullptr)
    (*sink_)(call, out_.files);
  else
    out_.calls.push_back(std::move(call));
}

}  // namespace truecut::interp
