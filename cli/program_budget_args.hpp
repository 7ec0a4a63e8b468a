// --max-blocks N: the interpreter's budget of executed blocks (loops and
// subroutine calls counted each time they run), which stops a program that
// never ends (InterpreterOptions::max_blocks).
#pragma once

#include <cstdint>

#include "args.hpp"

namespace truecut::cli {

inline constexpr const char* kMaxBlocksHelp =
    "  --max-blocks N      stop a program after N executed blocks, loops counted\n"
    "                      each time round (default 50000000: an endless loop?)\n";

// The option's value (default InterpreterOptions' 50,000,000), 1 .. 1e12.
std::int64_t max_blocks_from_args(const ParsedArgs& a);

}  // namespace truecut::cli
