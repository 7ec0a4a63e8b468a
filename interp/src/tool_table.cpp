#include "truecut/interp/tool_table.hpp"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

#include "source_text.hpp"
#include "truecut/interp/error.hpp"

namespace truecut::interp {

namespace {

double parse_number(const std::string& text, size_t start, size_t end, const std::string& file,
                    int line) {
  const std::string s = text.substr(start + 1, end - start - 1);
  char* stop = nullptr;
  const double v = std::strtod(s.c_str(), &stop);
  if (s.empty() || *stop != '\0')
    throw GcodeError({file, line, static_cast<int>(start) + 1},
                     std::string("bad number after '") + text[start] + "' in tool table");
  if (!std::isfinite(v))
    throw GcodeError({file, line, static_cast<int>(start) + 1},
                     std::string("'") + text[start] + s + "' in tool table: not a finite number");
  return v;
}

// Plausibility: a value outside [lo, hi] is a typo or a unit mix-up, not a
// tool (the limits are far beyond any milling tool).
void check_range(double v, double lo, double hi, const char* what, const std::string& file,
                 int line, size_t column) {
  if (v >= lo && v <= hi) return;
  char b[200];
  std::snprintf(b, sizeof b, "%s %.6g in tool table is outside %g to %g", what, v, lo, hi);
  throw GcodeError({file, line, static_cast<int>(column) + 1}, b);
}

int whole_number(double v, const char* what, const std::string& file, int line, size_t column) {
  check_range(v, 0, 99999, what, file, line, column);
  if (v != std::floor(v)) {
    char b[160];
    std::snprintf(b, sizeof b, "%s %.6g in tool table is not a whole number", what, v);
    throw GcodeError({file, line, static_cast<int>(column) + 1}, b);
  }
  return static_cast<int>(v);
}

constexpr double kMaxDiameterMm = 1000.0;  // a 1 m cutter
constexpr double kMaxOffsetMm = 10000.0;   // 10 m of tool length or offset
constexpr double kMaxAngleDeg = 3600.0;

}  // namespace

void ToolTable::add(ToolEntry entry) {
  for (auto& e : entries_) {
    if (e.number == entry.number) {
      e = std::move(entry);
      return;
    }
  }
  entries_.push_back(std::move(entry));
}

const ToolEntry* ToolTable::find(int number) const {
  for (const auto& e : entries_)
    if (e.number == number) return &e;
  return nullptr;
}

ToolEntry* ToolTable::find(int number) {
  for (auto& e : entries_)
    if (e.number == number) return &e;
  return nullptr;
}

std::optional<int> ToolTable::slot_of(int number) const {
  for (size_t i = 0; i < entries_.size(); ++i)
    if (entries_[i].number == number) return static_cast<int>(i) + 1;
  return std::nullopt;
}

ToolTable ToolTable::parse(std::string_view text, const std::string& name, LengthUnits units) {
  // Lengths are checked in the table's units and stored in mm.
  const double to_mm = units == LengthUnits::kInch ? 25.4 : 1.0;
  ToolTable table;
  table.units_ = units;
  const SourceFile src = source_from_text(text, name);
  std::map<int, int> line_of_tool;  // where each tool number was given
  for (size_t li = 0; li < src.lines.size(); ++li) {
    const int line = static_cast<int>(li) + 1;
    std::string s = src.lines[li];
    std::string comment;
    if (auto semi = s.find(';'); semi != std::string::npos) {
      comment = s.substr(semi + 1);
      s.resize(semi);
    }
    ToolEntry e;
    bool has_t = false;
    std::map<char, size_t> column_of_field;  // a field given twice on a line
    size_t i = 0;
    while (i < s.size()) {
      if (std::isspace(static_cast<unsigned char>(s[i]))) {
        ++i;
        continue;
      }
      size_t end = i + 1;
      while (end < s.size() && !std::isspace(static_cast<unsigned char>(s[end])))
        ++end;
      const char key = static_cast<char>(std::toupper(static_cast<unsigned char>(s[i])));
      const double v = parse_number(s, i, end, name, line);
      const double v_mm = v * to_mm;
      if (const auto [at, first] = column_of_field.try_emplace(key, i); !first)
        throw GcodeError({name, line, static_cast<int>(i) + 1},
                         std::string("field '") + key +
                             "' is given twice on this line (also at column " +
                             std::to_string(at->second + 1) +
                             "): which one is meant? (LinuxCNC takes the last)");
      switch (key) {
        case 'T':
          e.number = whole_number(v, "tool number T", name, line, i);
          has_t = true;
          break;
        case 'P':
          e.pocket = whole_number(v, "pocket P", name, line, i);
          break;
        case 'X':
        case 'Y':
        case 'Z': {
          check_range(v, -kMaxOffsetMm / to_mm, kMaxOffsetMm / to_mm,
                      key == 'X'   ? "offset X"
                      : key == 'Y' ? "offset Y"
                                   : "offset Z (length)",
                      name, line, i);
          (key == 'X' ? e.offset_mm.x : key == 'Y' ? e.offset_mm.y : e.offset_mm.z) = v_mm;
          break;
        }
        case 'A':
        case 'B':
        case 'C':
          check_range(v, -kMaxAngleDeg, kMaxAngleDeg, "angular offset", name, line, i);
          (key == 'A' ? e.offset_mm.a : key == 'B' ? e.offset_mm.b : e.offset_mm.c) = v;
          break;
        case 'D':
          check_range(v, 0.0, kMaxDiameterMm / to_mm, "diameter D", name, line, i);
          e.diameter_mm = v_mm;
          break;
        case 'U':
        case 'V':
        case 'W':
          break;
        case 'I':
        case 'J':
          check_range(v, -kMaxAngleDeg, kMaxAngleDeg, key == 'I' ? "front angle I" : "back angle J",
                      name, line, i);
          (key == 'I' ? e.front_angle_deg : e.back_angle_deg) = v;
          break;
        case 'Q':
          e.orientation = whole_number(v, "orientation Q", name, line, i);
          if (e.orientation > 9)
            throw GcodeError({name, line, static_cast<int>(i) + 1},
                             "tool orientation Q must be 0..9");
          break;
        default:
          throw GcodeError({name, line, static_cast<int>(i) + 1},
                           std::string("unknown tool table field '") + s[i] + "'");
      }
      i = end;
    }
    if (!has_t) {
      if (s.find_first_not_of(" \t") == std::string::npos) continue;  // blank or comment only
      throw GcodeError({name, line, 1}, "tool table line without T<number>");
    }
    if (const auto [at, first] = line_of_tool.try_emplace(e.number, line); !first)
      throw GcodeError({name, line, 1}, "tool T" + std::to_string(e.number) +
                                            " is already in the table at line " +
                                            std::to_string(at->second) +
                                            ": two entries for one tool (LinuxCNC keeps the "
                                            "last); remove one");
    const size_t first = comment.find_first_not_of(' ');
    e.comment = first == std::string::npos ? "" : comment.substr(first);
    table.add(std::move(e));
  }
  return table;
}

ToolTable ToolTable::load(const std::filesystem::path& file, LengthUnits units) {
  return parse(read_located_file(file, "tool table"), file.string(), units);
}

}  // namespace truecut::interp
