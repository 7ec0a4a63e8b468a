// The table of subcommands, filled by the static registrations of cmd_*.cpp.
#include <algorithm>

#include "commands.hpp"

namespace truecut::cli {
namespace {

std::vector<Command>& registry() {
  static std::vector<Command> table;  // function-local: safe during static initialisation
  return table;
}

}  // namespace

const std::vector<Command>& commands() {
  return registry();
}

CommandRegistration::CommandRegistration(const char* name, const char* summary, CommandFunction run,
                                         int order) {
  auto& table = registry();
  table.push_back({name, summary, run, order});
  std::stable_sort(table.begin(), table.end(),
                   [](const Command& a, const Command& b) { return a.order < b.order; });
}

}  // namespace truecut::cli
