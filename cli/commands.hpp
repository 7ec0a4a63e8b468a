// The truecut subcommands. Each cmd_<name>.cpp registers itself with a
// static CommandRegistration, so adding a command touches no shared file.
// A command takes the arguments after its name and returns an exit code
// (0 ok, 1 runtime failure, 2 usage or input error).
#pragma once

#include <string>
#include <vector>

namespace truecut::cli {

using CommandFunction = int (*)(const std::vector<std::string>& args);

struct Command {
  const char* name;
  const char* summary;
  CommandFunction run;
  int order;  // position in `truecut --help` (the data flow's order)
};

// Every registered command, sorted by order.
const std::vector<Command>& commands();

struct CommandRegistration {
  CommandRegistration(const char* name, const char* summary, CommandFunction run, int order);
};

}  // namespace truecut::cli
