// A read position in a lexed line, and errors located at a column of it.
#pragma once

#include <string>

#include "line_lexer.hpp"
#include "truecut/interp/error.hpp"

namespace truecut::interp {

// Brackets and function calls nested deeper than this are refused: each
// level is a recursion of the expression reader, and no program written by
// hand or by a CAM system comes near it.
constexpr int kMaxExpressionNesting = 1000;

struct Cursor {
  const LexedLine* line;
  size_t pos = 0;
  int nesting = 0;  // brackets open at pos

  bool at_end() const { return pos >= line->text.size(); }
  char peek(size_t ahead = 0) const {
    return pos + ahead < line->text.size() ? line->text[pos + ahead] : '\0';
  }
  bool starts_with(const char* word) const {
    return line->text.compare(pos, std::char_traits<char>::length(word), word) == 0;
  }
  int column_at(size_t at) const {
    return at < line->column.size() ? line->column[at] : line->end_column;
  }
  SourceLocation where(size_t at) const { return {*line->file, line->line, column_at(at)}; }
  [[noreturn]] void fail_at(size_t at, const std::string& message) const {
    throw GcodeError(where(at), message);
  }
  [[noreturn]] void fail(const std::string& message) const { fail_at(pos, message); }
};

}  // namespace truecut::interp
