// Pieces both forms of `truecut run` share: where components are found, the
// progress line on stderr, Ctrl-C handling.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "args.hpp"
#include "truecut/rt/executor.hpp"
#include "truecut/rt/hal.hpp"

namespace truecut::cli {

// Exit status of a run stopped by Ctrl-C before it was done: 128 + SIGINT,
// what a shell reports for a process that Ctrl-C ended.
constexpr int kExitInterrupted = 130;

// --component-path folders, then $TRUECUT_COMPONENT_PATH, then the folders
// beside the truecut binary.
std::vector<std::filesystem::path> component_path(const ParsedArgs& a);

// Progress on a terminal at most once per second of run time: "t / total
// (p%)" on one carriage-return line (quiet_option.hpp: on a terminal only).
struct Progress {
  int64_t total_ns = 0;
  int64_t last_ns = -1;
};
void print_progress(void* user, int64_t time_ns);

// Runs the executor with Ctrl-C asking the HAL to stop; `interrupted` says
// whether it did (a component's stop request is not an interrupt).
struct InterruptibleRun {
  rt::hal::RunReport report;
  bool interrupted = false;
};
InterruptibleRun run_interruptible(rt::hal::Hal& h, const rt::hal::RunLimits& limits,
                                   bool wall_clock, const rt::hal::WallClockOptions& wall);

}  // namespace truecut::cli
