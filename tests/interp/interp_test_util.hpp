// Helpers for the interpreter suites: run G-code text, print the calls like
// rs274 (without counters), catch the located error of a bad program.
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "truecut/interp/error.hpp"
#include "truecut/interp/interpreter.hpp"
#include "truecut/interp/rs274_format.hpp"

namespace truecut::interp::testing {

// T1: Z 10 mm, T2: X 1 mm and Z 20 mm, T7 in row 3.
inline ToolTable sample_tools() {
  return ToolTable::parse(
      "T1 P1 D6 Z10 ;6 mm end mill\n"
      "T2 P2 D3 X1 Z20 ;3 mm ball\n"
      "T7 P9 D10 Z-5\n",
      "tools.tbl");
}

inline CanonProgram run(const std::string& text, InterpreterOptions options = {}) {
  if (options.tools.entries().empty()) options.tools = sample_tools();
  return Interpreter(std::move(options)).run_text(text, "test.ngc");
}

// Every call as rs274 prints it, 4 decimals, without the six start-up calls.
inline std::vector<std::string> calls(const CanonProgram& p, int decimals = 4) {
  std::vector<std::string> out;
  for (size_t i = 6; i < p.calls.size(); ++i)
    out.push_back(format_rs274(p.calls[i].op, FormatOptions{decimals}));
  return out;
}

// Only the calls whose name starts with one of `prefixes`.
inline std::vector<std::string> calls_named(const CanonProgram& p,
                                            std::vector<std::string> prefixes) {
  std::vector<std::string> out;
  for (const auto& s : calls(p))
    for (const auto& pre : prefixes)
      if (s.rfind(pre + "(", 0) == 0) out.push_back(s);
  return out;
}

inline std::vector<std::string> moves(const CanonProgram& p) {
  return calls_named(p, {"STRAIGHT_TRAVERSE", "STRAIGHT_FEED", "ARC_FEED"});
}

// The error of a program that must fail; an empty error when it runs.
inline GcodeError error_of(const std::string& text, InterpreterOptions options = {}) {
  try {
    run(text, std::move(options));
  } catch (const GcodeError& e) {
    return e;
  }
  ADD_FAILURE() << "program ran without error:\n" << text;
  return GcodeError({}, "");
}

}  // namespace truecut::interp::testing
