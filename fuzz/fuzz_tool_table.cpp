// LinuxCNC tool tables.
#include <cstdint>
#include <stdexcept>
#include <string>

#include "fuzz_input.hpp"
#include "truecut/interp/tool_table.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    truecut::interp::ToolTable::parse(truecut::fuzz::as_text(data, size), "fuzz.tbl");
  } catch (const std::runtime_error&) {
  }
  return 0;
}
