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

}  // namespace truecut::test
