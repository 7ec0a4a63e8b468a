// Errors in a G-code program or its inputs, located as file:line:column.
#pragma once

#include <stdexcept>
#include <string>

namespace truecut::interp {

struct SourceLocation {
  std::string file;
  int line = 0;    // 1-based; 0 when the error concerns the whole file
  int column = 0;  // 1-based byte column; 0 when unknown
};

class GcodeError : public std::runtime_error {
 public:
  GcodeError(SourceLocation where, std::string message);
  const SourceLocation& where() const { return where_; }
  const std::string& message() const { return message_; }

 private:
  SourceLocation where_;
  std::string message_;
};

}  // namespace truecut::interp
