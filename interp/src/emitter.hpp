// Appends canonical calls to a program with the context in force.
#pragma once

#include <string>

#include "interp_state.hpp"
#include "truecut/interp/canon.hpp"

namespace truecut::interp {

class Emitter {
 public:
  // `sink`: when set, each call goes there instead of into out.calls.
  Emitter(CanonProgram& out, const InterpState& state, const CanonSink* sink = nullptr)
      : out_(out), state_(state), sink_(sink != nullptr && *sink ? sink : nullptr) {}
  void set_location(int file, int line, std::string block_number = {}) {
    file_ = file;
    line_ = line;
    block_number_ = std::move(block_number);
  }
  // Calls after the program has ended (rs274's closing ON_RESETs) belong to
  // no block: no N number.
  void clear_block_number() { block_number_.clear(); }
  void emit(CanonOp op, double inverse_time_f = 0);

 private:
  CanonProgram& out_;
  const InterpState& state_;
  const CanonSink* sink_;
  int file_ = 0;
  int line_ = 0;
  std::string block_number_;
};

}  // namespace truecut::interp
