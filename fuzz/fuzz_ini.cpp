// INI files.
#include <cstdint>
#include <stdexcept>
#include <string>

#include "fuzz_input.hpp"
#include "truecut/rt/ini.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    truecut::rt::hal::Ini::parse(std::string(truecut::fuzz::as_text(data, size)), "fuzz.ini");
  } catch (const std::runtime_error&) {
  }
  return 0;
}
