#include "truecut/interp/interpreter.hpp"

#include "program_runner.hpp"
#include "source_text.hpp"

namespace truecut::interp {

Interpreter::Interpreter(InterpreterOptions options) : options_(std::move(options)) {}

CanonProgram Interpreter::run_file(const std::filesystem::path& program) const {
  CanonProgram out;
  ProgramRunner runner(options_, out);
  runner.run(load_source(program));
  return out;
}

CanonProgram Interpreter::run_text(std::string_view text, const std::string& name) const {
  CanonProgram out;
  ProgramRunner runner(options_, out);
  runner.run(source_from_text(text, name));
  return out;
}

}  // namespace truecut::interp
