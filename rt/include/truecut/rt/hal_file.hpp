// Reader for `.hal` wiring files, the halcmd subset truecut supports:
//
//   loadrt MODULE [key=value ...]      loadrt threads name1=T period1=NS [fp1=0|1]
//   newthread NAME PERIOD_NS [fp|nofp]
//   addf FUNCT THREAD [POSITION]       (1 = first, -1 = last, the default)
//   net SIGNAL PIN [=>|<=|<=> PIN ...] newsig SIGNAL TYPE
//   linkps PIN SIGNAL / linksp SIGNAL PIN / unlinkp PIN
//   setp NAME VALUE  /  NAME = VALUE   sets SIGNAL VALUE
//   source FILE                        start / stop (accepted, no effect)
//
// `#` starts a comment, a trailing `\` continues a line, "double quotes" keep
// spaces, and `[SECTION]KEY` anywhere in a word is replaced from the INI file.
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>

#include "truecut/rt/hal.hpp"
#include "truecut/rt/ini.hpp"

namespace truecut::rt::hal {

// "file:line: message"
class HalFileError : public std::runtime_error {
 public:
  HalFileError(const std::string& file, int line, const std::string& message);
  const std::string& file() const { return file_; }
  int line() const { return line_; }
  const std::string& message() const { return message_; }

 private:
  std::string file_;
  int line_;
  std::string message_;
};

void load_hal_file(Hal& hal, const std::filesystem::path& file, const Ini* ini = nullptr);
// `file_name` is used in messages; `source` paths resolve against `base_dir`.
void load_hal_text(Hal& hal, const std::string& text, const std::string& file_name,
                   const Ini* ini = nullptr, const std::filesystem::path& base_dir = ".");

}  // namespace truecut::rt::hal
