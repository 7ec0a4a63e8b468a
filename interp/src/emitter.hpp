// Appends canonical calls to a program with the context in force.
#pragma once

#include "interp_state.hpp"
#include "truecut/interp/canon.hpp"

namespace truecut::interp {

class Emitter {
 public:
  // `sink`: when set, each call goes there instead of into out.calls.
  Emitter(CanonProgram& out, const InterpState& state, const CanonSink* sink = nullptr)
      : out_(out), state_(state), sink_(sink != nullptr && *sink ? sink : nullptr) {}
  void set_location(int file, int line) {
    file_ = file;
    line_ = line;
  }
  void emit(CanonOp op, double inverse_time_f = 0);

 private:
  CanonProgram& out_;
  const InterpState& state_;
  const CanonSink* sink_;
  int file_ = 0;
  int line_ = 0;
};

}  // namespace truecut::interp
