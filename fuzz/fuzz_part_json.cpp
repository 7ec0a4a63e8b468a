// part.json (surfaces, datums, operations of a part).
#include <cstdint>
#include <stdexcept>
#include <string>

#include "fuzz_input.hpp"
#include "truecut/sim/part_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    truecut::sim::parse_part_file(truecut::fuzz::as_text(data, size), "fuzz.json");
  } catch (const std::runtime_error&) {
  }
  return 0;
}
