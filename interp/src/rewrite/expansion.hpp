// Loops and subroutine calls the rewrite writes out move by move
// (docs/rewrite.md, "Expanded loops and calls"). A feed move of the
// operation that runs more than once, or that sits in a subroutine file,
// cannot be corrected on its own line: the outermost loop or calling line of
// the main program around it is replaced by the moves it makes.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "raw_lines.hpp"
#include "truecut/interp/canon.hpp"

namespace truecut::interp::rewrite {

struct Expansion {
  int first_line = 0;  // main-program lines replaced, 1-based, inclusive
  int last_line = 0;
  std::string what;  // "the loop o100 (while ... endwhile)", "the call o<pocket> call"
  std::string why;   // "feed moves of operation 'x' run more than once"
};

using Expansions = std::map<int, Expansion>;  // by first line

// A NURBS block (G5.2 ... G5.3) of the operation: its lines, and the
// main-program line that ran it (its last line, or a calling line).
struct NurbsBlock {
  int first_line = 0, last_line = 0;
  int outer_line = 0;
};

// The expansions `program` needs for `operation` (its NURBS blocks given).
// Throws GcodeError, at the line, for a loop whose end cannot be found, a
// subroutine definition or a canned cycle inside an expansion.
Expansions find_expansions(const CanonProgram& program, const std::vector<RawLine>& raw,
                           const std::string& name, const std::string& operation,
                           const std::vector<NurbsBlock>& nurbs_blocks);

// The expansion whose lines hold main-program line `outer_line`, or null.
const Expansion* expansion_at(const Expansions& expansions, int outer_line);

}  // namespace truecut::interp::rewrite
