// G-code programs (and the expressions, parameters and O-words in them)
// through the interpreter: any input ends in a program or a GcodeError.
#include <cstdint>
#include <stdexcept>
#include <string>

#include "fuzz_input.hpp"
#include "truecut/interp/interpreter.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  truecut::interp::InterpreterOptions options;
  options.max_blocks = 100'000;  // an endless loop is an error, found quickly
  try {
    truecut::interp::Interpreter(options).run_text(truecut::fuzz::as_text(data, size), "fuzz.ngc");
  } catch (const std::runtime_error&) {
  }
  return 0;
}
