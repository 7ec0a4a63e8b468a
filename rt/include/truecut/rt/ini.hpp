// LinuxCNC-style INI files: `[SECTION]` headers, `KEY = VALUE` lines,
// comments starting with `#` or `;`. The first occurrence of a key wins, as
// with LinuxCNC's inifile lookups.
#pragma once

#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>

namespace truecut::rt::hal {

class IniError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Ini {
 public:
  Ini() = default;
  // Throws IniError "file:line: message" on a malformed line or unreadable file.
  static Ini load(const std::filesystem::path& file);
  static Ini parse(const std::string& text, const std::string& file_name);

  std::optional<std::string> find(const std::string& section, const std::string& key) const;
  void set(const std::string& section, const std::string& key, const std::string& value);
  const std::string& file_name() const { return file_name_; }

 private:
  std::string file_name_;
  std::map<std::pair<std::string, std::string>, std::string> values_;
};

}  // namespace truecut::rt::hal
