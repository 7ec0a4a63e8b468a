// Machine descriptions (JSON).
#include <cstdint>
#include <stdexcept>
#include <string>

#include "fuzz_input.hpp"
#include "truecut/sim/machine_description.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    truecut::sim::parse_machine_description(std::string(truecut::fuzz::as_text(data, size)),
                                            "fuzz.json");
  } catch (const std::runtime_error&) {
  }
  return 0;
}
