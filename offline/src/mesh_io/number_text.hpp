// Number parsing and formatting for the text formats. Formatting uses the
// shortest representation that reads back to the identical double, so text
// round trips are exact.
#pragma once

#include <charconv>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace truecut::offline::mesh_io {

// Accepts a leading '+', and "nan"/"inf" (the callers report non-finite values
// as such rather than as "not a number").
inline bool parse_double(std::string_view text, double& out) {
  const char* b = text.data();
  const char* e = b + text.size();
  if (b != e && *b == '+') ++b;
  auto [ptr, ec] = std::from_chars(b, e, out);
  return ec == std::errc() && ptr == e && b != e;
}

inline bool parse_int(std::string_view text, std::int64_t& out) {
  const char* b = text.data();
  const char* e = b + text.size();
  if (b != e && *b == '+') ++b;
  auto [ptr, ec] = std::from_chars(b, e, out);
  return ec == std::errc() && ptr == e && b != e;
}

inline void append_double(std::string& out, double value) {
  char buf[32];
  auto [ptr, ec] = std::to_chars(buf, buf + sizeof buf, value);
  out.append(buf, ptr);
}

inline void append_uint(std::string& out, std::uint64_t value) {
  char buf[24];
  auto [ptr, ec] = std::to_chars(buf, buf + sizeof buf, value);
  out.append(buf, ptr);
}

inline bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v';
}

// Splits on runs of blanks; `out` is reused to avoid allocating per line.
inline void split_blanks(std::string_view line, std::vector<std::string_view>& out) {
  out.clear();
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_space(line[i]))
      ++i;
    std::size_t b = i;
    while (i < line.size() && !is_space(line[i]))
      ++i;
    if (i > b) out.push_back(line.substr(b, i - b));
  }
}

inline std::string_view trim_blanks(std::string_view s) {
  while (!s.empty() && is_space(s.front()))
    s.remove_prefix(1);
  while (!s.empty() && is_space(s.back()))
    s.remove_suffix(1);
  return s;
}

// Quotes a token for an error message, shortened so binary junk stays readable.
inline std::string quote_token(std::string_view token) {
  std::string out = "'";
  for (char c : token.substr(0, 40))
    out += (static_cast<unsigned char>(c) < 0x20) ? '?' : c;
  if (token.size() > 40) out += "...";
  return out + "'";
}

}  // namespace truecut::offline::mesh_io
