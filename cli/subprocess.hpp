// Runs another program (truecut itself, for the demo's steps) with its
// output appended to a log file.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace truecut::cli {

// Runs argv[0] with argv in the folder `cwd` (the caller's own working
// folder is not touched, so threads may run steps at once), stdout and
// stderr appended to `log` (relative to the caller's folder); returns the
// exit code (-1 when killed by a signal). Throws std::runtime_error when the
// program cannot be started.
int run_logged(const std::vector<std::string>& argv, const std::filesystem::path& log,
               const std::filesystem::path& cwd = {});

// argv as a shell command line (arguments quoted where needed), for logs
// and the demo's commands.sh.
std::string shell_words(const std::vector<std::string>& argv);

}  // namespace truecut::cli
