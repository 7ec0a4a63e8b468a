// Recordings: CSV traces (any delimiter, units in the header) and EPICS
// camonitor logs, as `truecut diagnose` and `truecut iso230` read them.
#include <cstdint>
#include <stdexcept>
#include <string>

#include "fuzz_input.hpp"
#include "truecut/analysis/recording.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto file = truecut::fuzz::as_file(data, size, "fuzz.csv");
  try {
    if (truecut::analysis::is_camonitor_log(file))
      truecut::analysis::read_camonitor(file, {});
    else
      truecut::analysis::read_recording(file);
  } catch (const std::runtime_error&) {
  }
  return 0;
}
