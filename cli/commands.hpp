// The truecut subcommands. Each takes the arguments after its name and
// returns an exit code (0 ok, 1 runtime failure, 2 usage or input error).
#pragma once

#include <string>
#include <vector>

namespace truecut::cli {

int cmd_run(const std::vector<std::string>& args);
int cmd_canon(const std::vector<std::string>& args);
int cmd_part(const std::vector<std::string>& args);
int cmd_iso230(const std::vector<std::string>& args);

}  // namespace truecut::cli
