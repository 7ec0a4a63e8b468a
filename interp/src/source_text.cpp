#include "source_text.hpp"

#include <cstdio>
#include <fstream>
#include <sstream>

#include "truecut/interp/error.hpp"
#include "truecut/rt/input_file.hpp"

namespace truecut::interp {

namespace {

bool allowed_control(unsigned char c) {
  return c == '\t' || c == '\r' || c == '\f' || c == '\v';
}

}  // namespace

SourceFile source_from_text(std::string_view text, const std::string& name) {
  SourceFile src;
  src.name = name;
  int line = 1;
  int column = 1;
  std::string current;
  for (unsigned char c : text) {
    if (c == '\n') {
      if (!current.empty() && current.back() == '\r') current.pop_back();
      src.lines.push_back(std::move(current));
      current.clear();
      ++line;
      column = 1;
      continue;
    }
    if (c < 0x20 && !allowed_control(c)) {
      char msg[96];
      std::snprintf(msg, sizeof msg, "not a text file: control byte 0x%02x", unsigned(c));
      throw GcodeError({name, line, column}, msg);
    }
    current.push_back(static_cast<char>(c));
    ++column;
  }
  if (!current.empty()) {
    if (current.back() == '\r') current.pop_back();
    src.lines.push_back(std::move(current));
  }
  return src;
}

std::string read_located_file(const std::filesystem::path& file, const char* what) {
  try {
    return rt::read_input_file(file, what);
  } catch (const rt::InputFileError& e) {
    throw GcodeError({file.string(), 0, 0}, e.reason());
  }
}

SourceFile load_source(const std::filesystem::path& file) {
  return source_from_text(read_located_file(file, "program file"), file.string());
}

}  // namespace truecut::interp
