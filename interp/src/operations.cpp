#include "truecut/interp/operations.hpp"

#include <algorithm>
#include <cctype>

namespace truecut::interp {

namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front())))
    s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back())))
    s.remove_suffix(1);
  return s;
}

bool starts_with_keyword(std::string_view s, std::string_view kw) {
  if (s.size() < kw.size()) return false;
  for (size_t i = 0; i < kw.size(); ++i)
    if (std::toupper(static_cast<unsigned char>(s[i])) != kw[i]) return false;
  return true;
}

}  // namespace

std::optional<std::string> operation_from_comment(std::string_view comment) {
  std::string_view s = trim(comment);
  static constexpr std::string_view kKeywords[] = {"OPERATION", "TOOLPATH", "JOB", "OP"};
  for (std::string_view kw : kKeywords) {
    if (!starts_with_keyword(s, kw)) continue;
    std::string_view rest = s.substr(kw.size());
    // The keyword must end here: OPERATIONAL or OPTION are not markers.
    if (!rest.empty() && std::isalpha(static_cast<unsigned char>(rest.front()))) continue;
    rest = trim(rest);
    while (!rest.empty() && std::isdigit(static_cast<unsigned char>(rest.front())))
      rest.remove_prefix(1);
    rest = trim(rest);
    if (rest.empty() || (rest.front() != ':' && rest.front() != '=')) return std::nullopt;
    std::string_view name = trim(rest.substr(1));
    if (name.empty()) return std::nullopt;
    return std::string(name);
  }
  return std::nullopt;
}

std::vector<std::string> operation_names(const CanonProgram& program) {
  std::vector<std::string> names;
  for (const auto& c : program.calls) {
    const std::string& op = c.context.operation;
    if (!op.empty() && std::find(names.begin(), names.end(), op) == names.end())
      names.push_back(op);
  }
  return names;
}

std::vector<CanonCall> moves_of_operation(const CanonProgram& program, std::string_view name) {
  std::vector<CanonCall> moves;
  for (const auto& c : program.calls)
    if (c.context.operation == name && is_motion(c.op)) moves.push_back(c);
  return moves;
}

}  // namespace truecut::interp
