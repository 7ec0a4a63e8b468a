#include "truecut/rt/ini.hpp"

#include <fstream>
#include <sstream>

#include "text_util.hpp"
#include "truecut/rt/input_file.hpp"

namespace truecut::rt::hal {

Ini Ini::load(const std::filesystem::path& file) {
  try {
    return parse(read_input_file(file, "INI file"), file.string());
  } catch (const InputFileError& e) {
    throw IniError(e.what());
  }
}

Ini Ini::parse(const std::string& text, const std::string& file_name) {
  Ini ini;
  ini.file_name_ = file_name;
  std::string section;
  std::istringstream in(text);
  std::string raw;
  int line_no = 0;
  while (std::getline(in, raw)) {
    ++line_no;
    // A value is handed on as C text, which ends at a NUL: "RADIUS = 5<NUL>0"
    // was read as 5.
    if (const auto nul = raw.find('\0'); nul != std::string::npos)
      throw IniError(file_name + ":" + std::to_string(line_no) +
                     ": not a text file (a NUL byte at column " + std::to_string(nul + 1) + ")");
    std::string line = trim(raw);
    if (line.empty() || line[0] == '#' || line[0] == ';') continue;
    auto where = [&] { return file_name + ":" + std::to_string(line_no) + ": "; };
    if (line[0] == '[') {
      auto close = line.find(']');
      if (close == std::string::npos) throw IniError(where() + "section header without ']'");
      section = trim(line.substr(1, close - 1));
      if (section.empty()) throw IniError(where() + "empty section name");
      continue;
    }
    auto eq = line.find('=');
    if (eq == std::string::npos)
      throw IniError(where() + "expected KEY = VALUE, got '" + line + "'");
    if (section.empty()) throw IniError(where() + "KEY = VALUE before any [SECTION]");
    std::string key = trim(line.substr(0, eq));
    if (key.empty()) throw IniError(where() + "empty key");
    ini.values_.emplace(std::make_pair(section, key), trim(line.substr(eq + 1)));
  }
  return ini;
}

std::optional<std::string> Ini::find(const std::string& section, const std::string& key) const {
  auto it = values_.find({section, key});
  if (it == values_.end()) return std::nullopt;
  return it->second;
}

void Ini::set(const std::string& section, const std::string& key, const std::string& value) {
  values_[{section, key}] = value;
}

}  // namespace truecut::rt::hal
