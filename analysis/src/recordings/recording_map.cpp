// Canonical channel names and the --map column-map syntax.
#include <charconv>
#include <cmath>
#include <string_view>

#include "truecut/analysis/recording.hpp"

namespace truecut::analysis {
namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t'))
    s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t'))
    s.remove_suffix(1);
  return s;
}

std::optional<double> number(std::string_view s) {
  s = trim(s);
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  double v = 0;
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || ec != std::errc() || p != s.data() + s.size() || !std::isfinite(v))
    return std::nullopt;
  return v;
}

ChannelSource parse_source(const std::string& name, std::string_view text) {
  const std::string item = name + "=" + std::string(text);
  ChannelSource src;
  std::string_view base = text;
  if (const auto star = text.rfind('*'); star != std::string_view::npos) {
    if (auto k = number(text.substr(star + 1))) {
      if (*k == 0) throw RecordingError("--map " + item + ": the factor after '*' must not be 0");
      src.scale = *k;
      src.factor_given = true;
      base = trim(text.substr(0, star));
    } else if (trim(text.substr(0, star)) == "@index") {
      throw RecordingError("--map " + item + ": '@index*' needs a number (the sample period)");
    }
  }
  if (base == "@index") {
    src.from_index = true;
    if (name == "t" && src.scale <= 0)
      throw RecordingError("--map " + item + ": the sample period must be positive");
  } else if (!base.empty() && base.front() == '@') {
    throw RecordingError("--map " + item + ": unknown source '" + std::string(base) +
                         "' (only @index is built in)");
  } else {
    src.column = std::string(base);
  }
  if (!src.from_index && src.column.empty())
    throw RecordingError("--map " + item + ": no column name after '='");
  return src;
}

}  // namespace

bool is_rotary_joint(const std::string& joint) {
  return joint == "a" || joint == "c";
}

std::vector<std::string> canonical_channels() {
  std::vector<std::string> names{"t"};
  for (const char* j : kRecordingJoints)
    for (const char* kind : {"_cmd", "_act", "_meas"})
      names.push_back(std::string(j) + kind);
  for (const char* extra :
       {"feed", "spindle_power", "line", "tool", "tcp_true_x", "tcp_true_y", "tcp_true_z"})
    names.emplace_back(extra);
  return names;
}

bool is_canonical_channel(const std::string& name) {
  for (const auto& c : canonical_channels())
    if (c == name) return true;
  return false;
}

ColumnMap parse_column_map(const std::string& spec) {
  ColumnMap map;
  std::string_view rest = spec;
  while (!rest.empty()) {
    const auto comma = rest.find(',');
    const std::string_view item = trim(rest.substr(0, comma));
    rest = comma == std::string_view::npos ? std::string_view() : rest.substr(comma + 1);
    if (item.empty()) continue;
    const auto eq = item.find('=');
    if (eq == std::string_view::npos)
      throw RecordingError("--map item '" + std::string(item) + "' is not NAME=COLUMN");
    const std::string name(trim(item.substr(0, eq)));
    if (!is_canonical_channel(name)) {
      std::string list;
      for (const auto& c : canonical_channels())
        list += (list.empty() ? "" : " ") + c;
      throw RecordingError("--map " + std::string(item) + ": '" + name +
                           "' is not a recording channel; channels are: " + list);
    }
    if (map.count(name)) throw RecordingError("--map names '" + name + "' twice");
    map[name] = parse_source(name, trim(item.substr(eq + 1)));
  }
  return map;
}

}  // namespace truecut::analysis
