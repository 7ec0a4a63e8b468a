// HAL files: loadrt of the built-in components, net, setp, addf, ... into a
// fresh HAL each time (nothing runs).
#include <cstdint>
#include <stdexcept>
#include <string>

#include "fuzz_input.hpp"
#include "truecut/rt/hal.hpp"
#include "truecut/rt/hal_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    truecut::rt::hal::HalOptions options;
    options.output_dir = truecut::fuzz::as_file(nullptr, 0, "out.keep").parent_path();
    truecut::rt::hal::Hal hal(options);
    truecut::rt::hal::load_hal_text(hal, std::string(truecut::fuzz::as_text(data, size)),
                                    "fuzz.hal");
  } catch (const std::runtime_error&) {
  }
  return 0;
}
