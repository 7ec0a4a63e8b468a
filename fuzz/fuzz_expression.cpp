// Expressions alone: the input is the inside of G0 X[...].
#include <cstdint>
#include <stdexcept>
#include <string>

#include "fuzz_input.hpp"
#include "truecut/interp/interpreter.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string program =
      "G21 G90\nG0 X[" + std::string(truecut::fuzz::as_text(data, size)) + "]\nM2\n";
  truecut::interp::InterpreterOptions options;
  options.max_blocks = 100'000;
  try {
    truecut::interp::Interpreter(options).run_text(program, "fuzz.ngc");
  } catch (const std::runtime_error&) {
  }
  return 0;
}
