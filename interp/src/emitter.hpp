// Appends canonical calls to a program with the context in force.
#pragma once

#include "interp_state.hpp"
#include "truecut/interp/canon.hpp"

namespace truecut::interp {

class Emitter {
 public:
  Emitter(CanonProgram& out, const InterpState& state) : out_(out), state_(state) {}
  void set_location(int file, int line) {
    file_ = file;
    line_ = line;
  }
  void emit(CanonOp op, double inverse_time_f = 0);

 private:
  CanonProgram& out_;
  const InterpState& state_;
  int file_ = 0;
  int line_ = 0;
};

}  // namespace truecut::interp
