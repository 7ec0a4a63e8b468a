// Appends canonical calls to a program with the context in force.
//
// Cutter radius compensation needs the next move before it can place the
// end of the last one: while compensation holds moves back (hold()), the
// calls LinuxCNC queues with them (feed, spindle, coolant, dwell, comments)
// wait behind them and go out in order at flush(); every other call goes out
// at once, as in LinuxCNC's interpreter.
#pragma once

#include <string>
#include <vector>

#include "interp_state.hpp"
#include "truecut/interp/canon.hpp"

namespace truecut::interp {

// A call held back by cutter compensation. For moves: the direction of the
// programmed move in the plane (straights) or the swept angle in radians
// (arcs, 0 = never checked), for the gouge checks when the end moves.
struct HeldCall {
  CanonCall call;
  double direction[2] = {0, 0};
  double sweep_rad = 0;
};

class Emitter {
 public:
  // `sink`: when set, each call goes there instead of into out.calls.
  Emitter(CanonProgram& out, const InterpState& state, const CanonSink* sink = nullptr)
      : out_(out), state_(state), sink_(sink != nullptr && *sink ? sink : nullptr) {}
  void set_location(int file, int line, std::string block_number = {}) {
    file_ = file;
    line_ = line;
    block_number_ = std::move(block_number);
    ++executed_block_;
    outer_line_ = line;
    outer_loop_line_ = 0;
  }
  // Inside a subroutine or a loop of the main program (CallContext).
  void set_outer(int outer_line, int outer_loop_line) {
    outer_line_ = outer_line;
    outer_loop_line_ = outer_loop_line;
  }
  // Calls after the program has ended (rs274's closing ON_RESETs) belong to
  // no block: no N number.
  void clear_block_number() { block_number_.clear(); }
  void emit(CanonOp op, double inverse_time_f = 0);
  // Past any held moves, for the few comments LinuxCNC does not queue.
  void emit_now(CanonOp op) { deliver(make(std::move(op), 0)); }

  // Holds a move back (cutter compensation); returns it for the caller to
  // fill in its direction or sweep.
  HeldCall& hold(CanonOp op, double inverse_time_f = 0);
  std::vector<HeldCall>& held() { return held_; }
  // Sends the held calls in order. rs274 prints the block number of the
  // block being executed when they go out.
  void flush();
  // Forgets the held calls: rs274 never sends them when a program ends at
  // its closing '%' with compensation on.
  void discard_held() { held_.clear(); }

 private:
  CanonCall make(CanonOp op, double inverse_time_f) const;
  void deliver(CanonCall call);

  CanonProgram& out_;
  const InterpState& state_;
  const CanonSink* sink_;
  int file_ = 0;
  int line_ = 0;
  std::string block_number_;
  long executed_block_ = 0;
  int outer_line_ = 0;
  int outer_loop_line_ = 0;
  std::vector<HeldCall> held_;
};

}  // namespace truecut::interp
