// G-code programs through truecut rewrite (matrix mode, the program's first
// `(OPERATION: name)`) on a fixed grid of compensation points: any input
// ends in a rewritten program or a GcodeError / RewriteError. The rewrite
// re-reads its own output (self check), so the writer is exercised too.
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>

#include "fuzz_input.hpp"
#include "truecut/interp/rewrite.hpp"
#include "truecut/interp/tool_table.hpp"

namespace {

using truecut::interp::CompensationMatrixData;

// Two planes of points 3 mm apart over ±30 mm, at Z 0 and Z -5, each with a
// correction of a few hundredths of a mm.
const CompensationMatrixData& grid() {
  static const CompensationMatrixData m = [] {
    CompensationMatrixData d;
    for (double z : {0.0, -5.0})
      for (double x = -30; x <= 30; x += 3)
        for (double y = -30; y <= 30; y += 3) {
          d.positions_mm.emplace_back(x, y, z);
          d.vectors_mm.emplace_back(0.02, -0.01, z == 0 ? 0.005 : -0.008);
          d.valid.push_back(1);
          d.surface_ids.push_back(z == 0 ? 1 : 2);
        }
    return d;
  }();
  return m;
}

std::string operation_of(std::string_view text) {
  const std::string_view key = "(OPERATION:";
  const auto at = text.find(key);
  if (at == std::string_view::npos) return "OP";
  std::size_t b = at + key.size();
  while (b < text.size() && text[b] == ' ')
    ++b;
  std::size_t e = b;
  while (e < text.size() && text[e] != ')' && text[e] != '\n')
    ++e;
  // The API's precondition (the CLI refuses an empty --operation itself).
  return e > b ? std::string(text.substr(b, e - b)) : "OP";
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace truecut::interp;
  const std::string_view text = truecut::fuzz::as_text(data, size);
  RewriteOptions o;
  o.operation = operation_of(text);
  // The cut type from the input's length: all three paths get inputs.
  o.type = size % 3 == 0 ? CutType::kPeripheral : size % 3 == 1 ? CutType::kFace : CutType::kBall;
  o.interpreter.max_blocks = 20'000;  // an endless loop is an error, found quickly
  // Moves hundreds of metres long are legal and take their time to densify
  // (about 3 us a point): bounded like the blocks, so that slow means a defect.
  o.max_points = 20'000;
  o.interpreter.tools =
      ToolTable::parse("T1 P1 D6 Z50\nT2 P2 D10 Z40\nT3 P3 D0.5 Z30\n", "fuzz.tbl");
  try {
    rewrite_program(text, "fuzz.ngc", grid(), o);
  } catch (const std::runtime_error&) {
  }
  return 0;
}
