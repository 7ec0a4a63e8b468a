// Runs a program to completion and captures its exit code and output.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace truecut::test {

struct ProcessResult {
  int exit_code = -1;  // -1 when killed by a signal
  std::string out;
  std::string err;
};

ProcessResult run_process(const std::vector<std::string>& argv,
                          const std::filesystem::path& cwd = ".");

// The same with stderr on a pseudo terminal, as a user at a terminal sees it
// (`err` holds what the terminal showed; its line ends are "\r\n").
ProcessResult run_process_on_a_terminal(const std::vector<std::string>& argv,
                                        const std::filesystem::path& cwd = ".");

}  // namespace truecut::test
