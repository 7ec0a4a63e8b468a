// Reading an input file whole, with the checks every reader shares: it must
// be a regular file (not a folder, a device such as /dev/zero, or a pipe,
// which would be read without end) and no larger than the input budget.
//
//   std::string text = rt::read_input_file(path, "G-code program");
//
// The budget is 1024 MB unless the environment variable
// TRUECUT_MAX_INPUT_MB sets another (docs/reliability.md).
#pragma once

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

namespace truecut::rt {

class InputFileError : public std::runtime_error {
 public:
  InputFileError(const std::filesystem::path& path, const std::string& reason)
      : std::runtime_error(path.string() + ": " + reason), reason_(reason) {}
  // What is wrong, without the path (for callers that name the file their way).
  const std::string& reason() const { return reason_; }

 private:
  std::string reason_;
};

constexpr std::uintmax_t kDefaultMaxInputMb = 1024;

// The input budget in bytes: $TRUECUT_MAX_INPUT_MB (a positive whole
// number of MB) or kDefaultMaxInputMb. A malformed value is an error.
std::uintmax_t max_input_bytes();

// Throws InputFileError when `path` is missing, not a regular file, larger
// than max_input_bytes(), or cannot be read. `what` names the kind of file
// in the message ("is a folder, not a G-code program").
void check_input_file(const std::filesystem::path& path, std::string_view what);

// check_input_file, then the whole content.
std::string read_input_file(const std::filesystem::path& path, std::string_view what);

}  // namespace truecut::rt
