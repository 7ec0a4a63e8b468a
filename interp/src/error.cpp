#include "truecut/interp/error.hpp"

namespace truecut::interp {

namespace {

std::string locate(const SourceLocation& w, const std::string& message) {
  std::string s = w.file;
  if (w.line > 0) s += ":" + std::to_string(w.line);
  if (w.line > 0 && w.column > 0) s += ":" + std::to_string(w.column);
  return s + ": " + message;
}

}  // namespace

GcodeError::GcodeError(SourceLocation where, std::string message)
    : std::runtime_error(locate(where, message)),
      where_(std::move(where)),
      message_(std::move(message)) {}

}  // namespace truecut::interp
