// RS274/NGC interpreter as LinuxCNC reads it, plus the Sinumerik words
// TRAORI, TRAFOOF, BSPLINE and CSPLINE. It turns a program into canonical
// calls (canon.hpp); see docs/gcode.md for the supported language.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "truecut/interp/canon.hpp"
#include "truecut/interp/parameter_file.hpp"
#include "truecut/interp/probe.hpp"
#include "truecut/interp/tool_table.hpp"

namespace truecut::interp {

// The parameters of the main program at a moment of its run: #1..#5601 by
// number ([0] unused), and its named ones (its locals and the #<_globals>;
// lower case, without '#<' '>'), predefined names apart.
struct ParameterValues {
  std::vector<double> numbered;
  std::map<std::string, double> named;
};

struct InterpreterOptions {
  ToolTable tools;
  // The controller's parameters at the start (its .var file): the work
  // offsets, G92, G28/G30 homes. Empty: every parameter 0, G54 active.
  ParameterFile parameters;
  // The block-delete switch: when on, lines starting with '/' are skipped
  // (LinuxCNC's rs274 starts with it off).
  bool block_delete = false;
  // Axes present on the machine. truecut's machine is X Y Z A C: a B word is
  // rejected with a clear message unless has_b is set.
  bool has_b = false;
  // Where `o<name> call` looks for name.ngc after the program's own folder.
  std::vector<std::filesystem::path> subroutine_path;
  // Guard against programs that never end (runaway while loops).
  std::int64_t max_blocks = 50'000'000;
  // Called with the number of blocks executed so far after every
  // progress_every_blocks blocks (a long program shows progress); unset: never.
  std::function<void(std::int64_t blocks)> progress;
  std::int64_t progress_every_blocks = 1 << 16;
  // When set, every canonical call goes here as it is made, with the files
  // named so far (CanonProgram::files), and CanonProgram::calls stays empty:
  // a program of any length in constant memory.
  CanonSink on_call;
  // Answers the probing moves G38.2-G38.5. Unset: standalone_probe (as
  // LinuxCNC's rs274: never trips, no error). When set, a G38.2 or G38.4
  // whose probe does not trip is an error at its line, as on LinuxCNC.
  ProbeFunction probe;
  // Called the first time the main program, not inside a subroutine,
  // reaches one of these lines (1-based, before running it), with the
  // parameters then. The rewrite sets after a loop it writes out move by
  // move the parameters the loop set.
  std::set<int> watch_lines;
  std::function<void(int line, const ParameterValues& values)> on_watch_line;
};

class Interpreter {
 public:
  explicit Interpreter(InterpreterOptions options = {});

  // Interprets a whole program. Throws GcodeError (file:line:column) on the
  // first error; nothing is returned for a program with an error.
  CanonProgram run_file(const std::filesystem::path& program) const;
  // Same for a program held in memory; `name` is used in error locations and
  // its folder (if any) for subroutine files.
  CanonProgram run_text(std::string_view text, const std::string& name) const;

 private:
  InterpreterOptions options_;
};

}  // namespace truecut::interp
