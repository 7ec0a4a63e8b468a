#include "truecut/interp/tool_table.hpp"

#include <cctype>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "source_text.hpp"
#include "truecut/interp/error.hpp"
#include "truecut/rt/input_file.hpp"

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
  return v;
}

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

std::optional<int> ToolTable::slot_of(int number) const {
  for (size_t i = 0; i < entries_.size(); ++i)
    if (entries_[i].number == number) return static_cast<int>(i) + 1;
  return std::nullopt;
}

ToolTable ToolTable::parse(std::string_view text, const std::string& name) {
  ToolTable table;
  const SourceFile src = source_from_text(text, name);
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
      switch (key) {
        case 'T':
          e.number = static_cast<int>(v);
          has_t = true;
          break;
        case 'P':
          e.pocket = static_cast<int>(v);
          break;
        case 'X':
          e.offset_mm.x = v;
          break;
        case 'Y':
          e.offset_mm.y = v;
          break;
        case 'Z':
          e.offset_mm.z = v;
          break;
        case 'A':
          e.offset_mm.a = v;
          break;
        case 'B':
          e.offset_mm.b = v;
          break;
        case 'C':
          e.offset_mm.c = v;
          break;
        case 'D':
          e.diameter_mm = v;
          break;
        case 'U':
        case 'V':
        case 'W':
        case 'I':
        case 'J':
        case 'Q':
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
    const size_t first = comment.find_first_not_of(' ');
    e.comment = first == std::string::npos ? "" : comment.substr(first);
    table.add(std::move(e));
  }
  return table;
}

ToolTable ToolTable::load(const std::filesystem::path& file) {
  std::string text;
  try {
    text = rt::read_input_file(file, "tool table");
  } catch (const rt::InputFileError& e) {
    throw GcodeError({file.string(), 0, 0}, e.reason());
  }
  return parse(text, file.string());
}

}  // namespace truecut::interp
