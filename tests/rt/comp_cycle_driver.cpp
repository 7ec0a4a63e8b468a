// Runs exactly N servo cycles of truecut_comp on one path (comp_cycle_paths.hpp)
// for callgrind to count, after a warm-up it does not count:
//
//   valgrind --tool=callgrind --instr-atstart=no --collect-atstart=no
//            --toggle-collect='*::update(void*, long)'
//            comp_cycle_driver plain|cross-fade|joint|fault N     (one line)
//
// Instrumentation starts right before the N cycles and stops right after
// them (CALLGRIND_START/STOP_INSTRUMENTATION); --toggle-collect then counts
// only the instructions of truecut_comp's update function (and what it
// calls), the only function on the servo thread, not the executor's loop nor
// the driver writing the inputs. Without valgrind the markers do nothing and
// the driver just runs. Exit code 0 when the component was in the path's
// state after the cycles (printed), 1 when not, 2 on bad arguments.
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "comp_cycle_paths.hpp"

#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#define TRUECUT_HAVE_CALLGRIND_H 1
#else
#define CALLGRIND_START_INSTRUMENTATION
#define CALLGRIND_STOP_INSTRUMENTATION
#define TRUECUT_HAVE_CALLGRIND_H 0
#endif

using namespace truecut::test::comp;

namespace {

// The measured region, a function of its own so that a profile shows it.
__attribute__((noinline)) void measured_cycles(CyclePathRig& rig, unsigned long n) {
  CALLGRIND_START_INSTRUMENTATION;
  rig.cycles(n);
  CALLGRIND_STOP_INSTRUMENTATION;
}

}  // namespace

int main(int argc, char** argv) {
  const auto path = argc == 3 ? parse_cycle_path(argv[1]) : std::nullopt;
  char* end = nullptr;
  const unsigned long n = argc == 3 ? std::strtoul(argv[2], &end, 10) : 0;
  if (!path || n == 0 || *end != '\0') {
    std::fprintf(stderr, "usage: comp_cycle_driver plain|cross-fade|joint|fault CYCLES\n");
    return 2;
  }
  if (!TRUECUT_HAVE_CALLGRIND_H)
    std::printf("built without valgrind/callgrind.h: the markers do nothing\n");
  const auto dir = std::filesystem::temp_directory_path() /
                   ("truecut_comp_cycle_driver-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::string why;
  {
    CyclePathRig rig(*path, dir);
    measured_cycles(rig, n);
    why = rig.check();
  }
  std::filesystem::remove_all(dir);
  std::printf("%s: %lu cycles%s%s\n", cycle_path_name(*path), n, why.empty() ? ", state ok" : ", ",
              why.c_str());
  return why.empty() ? 0 : 1;
}
