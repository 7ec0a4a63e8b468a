// truecut <command> ...: the command-line front end.
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include "args.hpp"
#include "commands.hpp"

namespace {

struct Command {
  const char* name;
  const char* summary;
  int (*run)(const std::vector<std::string>&);
};

const Command kCommands[] = {
    {"run", "run a .hal configuration in the soft-CNC executor", truecut::cli::cmd_run},
    {"canon", "print the canonical calls of a G-code program", truecut::cli::cmd_canon},
    {"part", "write a benchmark part: nominal STL, CAM program, tools", truecut::cli::cmd_part},
    {"iso230", "ISO 230-2 positioning and ISO 230-4 circular test from a recording", truecut::cli::cmd_iso230},
};

void print_usage(std::FILE* to) {
  std::fprintf(to,
               "usage: truecut <command> [options]\n"
               "       truecut <command> --help\n\n"
               "commands:\n");
  for (const auto& c : kCommands)
    std::fprintf(to, "  %-10s %s\n", c.name, c.summary);
  std::fprintf(to, "\nexit codes: 0 ok, 1 runtime failure, 2 usage or input error\n");
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty()) {
    print_usage(stderr);
    return truecut::cli::kExitUsage;
  }
  if (args[0] == "--help" || args[0] == "-h" || args[0] == "help") {
    print_usage(stdout);
    return truecut::cli::kExitOk;
  }
  if (args[0] == "--version") {
    std::printf("truecut 0.1.0\n");
    return truecut::cli::kExitOk;
  }
  for (const auto& c : kCommands) {
    if (args[0] != c.name) continue;
    try {
      return c.run(std::vector<std::string>(args.begin() + 1, args.end()));
    } catch (const truecut::cli::UsageError& e) {
      std::fprintf(stderr, "truecut %s: %s\n(see truecut %s --help)\n", c.name, e.what(), c.name);
      return truecut::cli::kExitUsage;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "truecut %s: %s\n", c.name, e.what());
      return truecut::cli::kExitFailure;
    }
  }
  std::fprintf(stderr, "truecut: unknown command '%s'\n\n", args[0].c_str());
  print_usage(stderr);
  return truecut::cli::kExitUsage;
}
