// The rewritten program is interpreted again before it is handed out:
// outside the rewritten lines it must make the same calls, in the same
// context, as the original (nothing leaked from the new lines: motion mode,
// feed, distance mode ...), and every written G1 point must come out where
// it was meant to be.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "truecut/interp/canon.hpp"
#include "truecut/interp/interpreter.hpp"
#include "truecut/interp/rs274_format.hpp"

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
  // An expanded loop or call (expansion.hpp) on lines first..last_line:
  // per written move, whether it is a G0, the feed in force (in G93 the
  // line's F) and the context of the original move (an index into
  // contexts); the original's other calls (rs274 text, feeds apart) in
  // order, which the new lines must make.
  int last_line = 0;  // > 0: expanded
  std::vector<char> traverse_at;
  std::vector<double> feed_at;
  std::vector<std::uint32_t> context_at;
  std::vector<CallContext> contexts;
  std::vector<std::string> others;
};

// A move back from a corrected point to the original one, written before a
// line kept as it is: a G1, or a G0 before a rapid.
struct ReturnMove {
  Axes6 end;
  bool traverse = false;
};

struct CheckInput {
  const CanonProgram& original;
  const std::map<int, RewrittenLine>& rewritten;
  const std::vector<OutputLine>& origin;  // per output line
  const InterpreterOptions& options;
  const std::string& name;
  // Lines kept as they are after a G1 back to the original point (written
  // before them): where that G1 must end.
  const std::map<int, ReturnMove>* returns = nullptr;
};

// How the check prints calls to compare them.
inline FormatOptions check_format() {
  FormatOptions f;
  f.decimals = 9;
  return f;
}

// A comment the interpreter makes of a mode change ("interpreter: distance
// mode changed to incremental"), not one of the program.
inline bool is_interpreter_note(const Comment& c) {
  return c.text.rfind("interpreter: ", 0) == 0;
}

// Throws GcodeError at the original line where the programs part.
void check_rewrite(const std::string& text, const CheckInput& in);

}  // namespace truecut::interp::rewrite
