// Correction field files (.tcf): header and binary payload.
#include <cstdint>
#include <stdexcept>

#include "fuzz_input.hpp"
#include "truecut/rt/field_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    truecut::rt::decode_field_file(truecut::fuzz::as_text(data, size), "fuzz.tcf");
  } catch (const std::runtime_error&) {
  }
  return 0;
}
