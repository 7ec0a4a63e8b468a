// truecut <command> ...: the command-line front end.
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include "args.hpp"
#include "commands.hpp"
#include "truecut/rt/interrupt_cleanup.hpp"

namespace {

void print_usage(std::FILE* to) {
  std::fprintf(to,
               "usage: truecut <command> [options]\n"
               "       truecut <command> --help\n\n"
               "commands:\n");
  for (const auto& c : truecut::cli::commands())
    std::fprintf(to, "  %-10s %s\n", c.name, c.summary);
  std::fprintf(to,
               "\nexit codes: 0 ok, 1 runtime failure, 2 usage or input error, 130 interrupted\n"
               "(Ctrl-C); --quiet: only warnings and errors on stderr\n");
}

// A command's standard output is often its product (`truecut canon`'s
// calls) or its summary: when it could not all be written (a full disk, a
// closed pipe), the command has not succeeded.
int checked_stdout(const char* command, int code) {
  errno = 0;
  if (std::fflush(stdout) == 0 && !std::ferror(stdout)) return code;
  std::fprintf(stderr, "truecut %s: writing the standard output failed (%s)\n", command,
               errno ? std::strerror(errno) : "a full disk, or a closed pipe?");
  return code == truecut::cli::kExitOk ? truecut::cli::kExitFailure : code;
}

}  // namespace

int main(int argc, char** argv) {
  // Ctrl-C or kill while an output is written leaves no NAME.tmp behind.
  truecut::rt::remove_pending_files_on_signals();
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
  for (const auto& c : truecut::cli::commands()) {
    if (args[0] != c.name) continue;
    try {
      return checked_stdout(c.name, c.run(std::vector<std::string>(args.begin() + 1, args.end())));
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
