// The rewritten program is interpreted again before it is handed out:
// outside the rewritten lines it must make the same calls, in the same
// context, as the original (nothing leaked from the new lines: motion mode,
// feed, distance mode ...), and every written G1 point must come out where
// it was meant to be.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "truecut/interp/canon.hpp"
#include "truecut/interp/interpreter.hpp"

namespace truecut::interp::rewrite {

struct OutputLine {
  enum Kind { kVerbatim, kResidual, kMove };
  int source_line = 0;  // 1-based line of the original program
  Kind kind = kVerbatim;
};

struct RewrittenLine {
  CallContext context;          // of the original move
  bool traverse = false;        // a G0 written with all axes, else G1 lines
  std::vector<Axes6> expected;  // program position of each written G1
  // A canned-cycle line (>= 0: the axis it drills along): expected[0] is the
  // hole's bottom; its feeds run over the hole, the deepest ends there.
  int cycle_normal_axis = -1;
};

struct CheckInput {
  const CanonProgram& original;
  const std::map<int, RewrittenLine>& rewritten;
  const std::vector<OutputLine>& origin;  // per output line
  const InterpreterOptions& options;
  const std::string& name;
  // Lines kept as they are after a G1 back to the original point (written
  // before them): where that G1 must end.
  const std::map<int, Axes6>* returns = nullptr;
};

// Throws GcodeError at the original line where the programs part.
void check_rewrite(const std::string& text, const CheckInput& in);

}  // namespace truecut::interp::rewrite
