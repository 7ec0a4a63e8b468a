// Runs a program line by line: O-word control flow (subroutines, if, while,
// do, repeat, break, continue), parameter settings, block delete and the
// program end, handing every other block to the BlockExecutor.
#pragma once

#include <deque>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "block.hpp"
#include "block_executor.hpp"
#include "source_text.hpp"
#include "truecut/interp/interpreter.hpp"

namespace truecut::interp {

class ProgramRunner {
 public:
  ProgramRunner(const InterpreterOptions& options, CanonProgram& out);
  void run(SourceFile main_file);

 private:
  struct File {
    SourceFile source;
    std::vector<LexedLine> lines;
    std::vector<std::optional<OWord>> owords;  // per line, for jumps
    size_t end = 0;  // lines after a closing '%' are not part of the program
  };
  struct Loop {
    std::string label;
    OKeyword kind;  // kWhile, kDo or kRepeat
    size_t start;   // line index of the while/do/repeat line
    double remaining = 0;
  };
  struct Frame {
    int file = 0;
    size_t pc = 0;
    std::string label;  // subroutine label, "" at top level
    std::vector<Loop> loops;
    bool fanuc = false;       // called by M98: returns at M99
    double repeats_left = 0;  // M98 L: runs still to go after this one
    size_t start = 0;         // first line of the M98 subprogram's body
  };

  int add_file(SourceFile source);
  // The label of an O-word line, a computed one evaluated now.
  std::string label_at(int file, size_t index) const;
  std::optional<std::pair<int, size_t>> find_sub(const std::string& label, const LexedLine& at);
  size_t find_forward(int file, size_t from, const std::string& label,
                      std::initializer_list<OKeyword> kinds, const LexedLine& at) const;
  // Executes the line at the current frame's pc; false when the program ends.
  bool step();
  void control(const OWord& o, const LexedLine& line);
  // Loop `li` of the current frame ends at line index `end` of its file
  // (CanonProgram::loop_last_lines: the main program's outermost loops).
  void note_loop_end(size_t li, size_t end);
  void assign(const Block& block, const LexedLine& line);
  // M98 P.. [L..] and M99 (Fanuc-style subprograms); false when the line
  // has neither. `ends` is set when M99 ends the main program.
  bool fanuc_call_or_return(const Block& block, const LexedLine& line, bool& ends);
  [[noreturn]] void fail(const LexedLine& line, int column, const std::string& message) const;

  const InterpreterOptions& options_;
  CanonProgram& out_;
  InterpState state_;
  Parameters params_;
  Emitter emitter_;
  BlockExecutor executor_;
  // A deque: lexed lines point at their file's name, and the line being
  // executed is referenced while a call loads another file, so a loaded
  // file never moves.
  std::deque<File> files_;
  std::vector<Frame> frames_;
  std::map<std::string, std::pair<int, size_t>> subs_;
  // Subroutines rs274 would know by now: met in the flow or called.
  std::set<std::string> defined_subs_;
  std::map<std::string, std::pair<int, size_t>> fanuc_subs_;  // "O100" lines, the first of each
  std::int64_t blocks_ = 0;
  std::set<int> watched_;  // InterpreterOptions::watch_lines met so far
};

}  // namespace truecut::interp
