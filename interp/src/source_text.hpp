// Loading a program file: the text check (a binary file is an error, not
// garbage moves) and the split into lines.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace truecut::interp {

struct SourceFile {
  std::string name;                // as given, used in error locations
  std::vector<std::string> lines;  // without line terminators
};

// Throws GcodeError when the file cannot be read or is not text.
SourceFile load_source(const std::filesystem::path& file);
// The text of an input file (a program, tool table, parameter file: `what`
// names it in the message); GcodeError naming the file when it cannot be
// read or is not text.
std::string read_located_file(const std::filesystem::path& file, const char* what);
SourceFile source_from_text(std::string_view text, const std::string& name);

}  // namespace truecut::interp
