#include "program_budget_args.hpp"

#include "truecut/interp/interpreter.hpp"

namespace truecut::cli {

std::int64_t max_blocks_from_args(const ParsedArgs& a) {
  return a.integer("max-blocks", interp::InterpreterOptions{}.max_blocks, 1, 1'000'000'000'000L);
}

}  // namespace truecut::cli
