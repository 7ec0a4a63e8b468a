// One line of a program as read: its words, comments, parameter settings
// and O-word, before anything is executed.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "expression.hpp"
#include "line_lexer.hpp"

namespace truecut::interp {

struct Word {
  double value = 0;
  int column = 0;
};

struct CodeWord {  // G or M code, value x10 (G61.1 -> 611, M3 -> 30)
  int code = 0;
  int column = 0;
};

struct CommentText {
  std::string text;  // without the parentheses or ';'
  int column = 0;
  bool semicolon = false;  // a ';' comment (to the end of the line)
};

enum class OKeyword {
  kSub,
  kEndsub,
  kCall,
  kReturn,
  kIf,
  kElseif,
  kElse,
  kEndif,
  kWhile,
  kEndwhile,
  kDo,
  kRepeat,
  kEndrepeat,
  kBreak,
  kContinue,
  kFanucSub  // "O100" alone: a Fanuc-style subprogram (M98 P100 calls it, M99 returns)
};

struct OWord {
  std::string label;  // "100" or "<name>" (lower case); "" for a computed label not yet evaluated
  bool computed = false;  // o[expr] or o#n: evaluated with the parameters when the line is met
  OKeyword keyword = OKeyword::kSub;
  int column = 0;
  std::vector<double> args;         // call arguments
  std::optional<double> condition;  // if/elseif/while/repeat count/return value
};

struct Assignment {
  ParameterRef target;
  double value = 0;
  int column = 0;
};

struct Block {
  bool deleted = false;  // starts with '/'
  int line = 0;
  std::optional<OWord> o;
  std::vector<CodeWord> g;
  std::vector<CodeWord> m;
  std::array<std::optional<Word>, 26> letter;  // other words, by 'a'..'z'
  // Polar coordinates: @ (radius) and ^ (angle, degrees) in the XY plane.
  std::optional<Word> polar_radius, polar_angle;
  std::vector<CommentText> comments;
  std::vector<Assignment> assignments;
  std::vector<LexedLine::Keyword> sinumerik;

  const std::optional<Word>& operator[](char c) const { return letter[c - 'a']; }
  bool has(char c) const { return letter[c - 'a'].has_value(); }
  double value(char c) const { return letter[c - 'a']->value; }
  bool has_g(int code) const;
  bool has_m(int code) const;
  bool has_polar() const { return polar_radius || polar_angle; }
  int polar_column() const { return polar_radius ? polar_radius->column : polar_angle->column; }
};

// Reads a lexed line. Words are evaluated with the parameters as they were
// before the line; assignments are only collected (LinuxCNC sets them after
// the whole line is read). Throws GcodeError at the offending column.
Block read_block(const LexedLine& line, const Parameters& params, bool has_b);

// Just the O-word label and keyword of a line, without evaluating anything
// (used when skipping over lines to find the end of an if or loop). A
// computed label comes back with computed set and an empty label, unless
// params are given: then it is evaluated (errors throw, located).
std::optional<OWord> scan_oword(const LexedLine& line, const Parameters* params = nullptr);

}  // namespace truecut::interp
