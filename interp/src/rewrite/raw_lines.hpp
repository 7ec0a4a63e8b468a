// The program split into lines with their terminators kept, numbered as the
// interpreter numbers them (a line ends at '\n'; a '\r' before it belongs
// to the terminator), so untouched lines are copied byte for byte.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace truecut::interp::rewrite {

struct RawLine {
  std::string content;     // without terminator
  std::string terminator;  // "\n", "\r\n" or "" (last line without one)
};

inline std::vector<RawLine> split_raw_lines(std::string_view text) {
  std::vector<RawLine> out;
  size_t pos = 0;
  while (pos < text.size()) {
    const size_t nl = text.find('\n', pos);
    if (nl == std::string_view::npos) {
      out.push_back({std::string(text.substr(pos)), ""});
      break;
    }
    RawLine l{std::string(text.substr(pos, nl - pos)), "\n"};
    if (!l.content.empty() && l.content.back() == '\r') {
      l.content.pop_back();
      l.terminator = "\r\n";
    }
    out.push_back(std::move(l));
    pos = nl + 1;
  }
  return out;
}

}  // namespace truecut::interp::rewrite
