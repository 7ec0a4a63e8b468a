// LinuxCNC parameter files (.var), and a short program started from them:
// the setup they hold (active system, rotation, G92) reaches the
// interpreter's state and its first moves.
#include <cstdint>
#include <stdexcept>
#include <string>

#include "fuzz_input.hpp"
#include "truecut/interp/interpreter.hpp"
#include "truecut/interp/parameter_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace truecut::interp;
  try {
    const auto text = truecut::fuzz::as_text(data, size);
    InterpreterOptions o;
    o.parameters = ParameterFile::parse(
        text, "fuzz.var", size > 0 && (data[0] & 1) ? LengthUnits::kInch : LengthUnits::kMm);
    o.max_blocks = 1000;
    Interpreter(o).run_text("G0 X1 Y2 Z3\nG28\nG30\nG1 X4 F100\nG2 X5 Y3 I0.5 J0.5\nM2\n",
                            "fuzz.ngc");
  } catch (const std::runtime_error&) {
  }
  return 0;
}
