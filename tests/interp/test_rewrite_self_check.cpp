// The rewrite's self-check names the file a disagreeing call belongs to
// (issue 23: `rewrite` blamed "line 1811" of a program with fewer lines, the
// line being one of a subroutine file or of the new program).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "self_check.hpp"
#include "test_paths.hpp"
#include "truecut/interp/error.hpp"
#include "truecut/interp/interpreter.hpp"

using namespace truecut::interp;
namespace fs = std::filesystem;

namespace {

std::string check_error(const std::string& original_text, const std::string& new_text,
                        const fs::path& sub_dir) {
  InterpreterOptions options;
  options.subroutine_path = {sub_dir};
  const CanonProgram original = Interpreter(options).run_text(original_text, "p.ngc");
  const std::map<int, rewrite::RewrittenLine> rewritten;
  std::vector<rewrite::OutputLine> origin;
  for (int i = 1; i <= 40; ++i)
    origin.push_back({i, rewrite::OutputLine::kVerbatim});
  try {
    rewrite::check_rewrite(new_text, {original, rewritten, origin, options, "p.ngc"});
  } catch (const GcodeError& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

TEST(RewriteSelfCheck, ACallOfASubroutineFileIsNamedInThatFile) {
  const fs::path dir = truecut::test::scratch_dir();
  std::ofstream(dir / "pocket.ngc") << "o<pocket> sub\n"
                                       "G1 X1 F100\n"
                                       "G1 Y1\n"
                                       "o<pocket> endsub\n"
                                       "M2\n";
  const std::string original = "G21 G90\nG0 X0 Y0 Z5\no<pocket> call\nG0 Z10\nM2\n";
  // The new program lost the call: the first call it lacks is line 2 of
  // pocket.ngc, not line 2 of p.ngc.
  const std::string lost = "G21 G90\nG0 X0 Y0 Z5\n\nG0 Z10\nM2\n";
  const std::string msg = check_error(original, lost, dir);
  EXPECT_NE(std::string::npos, msg.find("pocket.ngc:2")) << msg;
  EXPECT_EQ(std::string::npos, msg.find("p.ngc:2")) << msg;
  EXPECT_NE(std::string::npos, msg.find("cannot be rewritten")) << msg;
}

TEST(RewriteSelfCheck, ALineOfTheNewProgramIsNotCalledALineOfTheOriginal) {
  const fs::path dir = truecut::test::scratch_dir();
  const std::string original = "G21 G90\nG0 X0 Y0 Z5\nG1 X1 F100\nM2\n";
  // Line 3 of the new program maps to nothing of the original (origin holds
  // 40 verbatim lines, so give it a line beyond them).
  std::string changed = "G21 G90\nG0 X0 Y0 Z5\n";
  for (int i = 0; i < 45; ++i)
    changed += "\n";
  changed += "G1 X2 F100\nM2\n";
  const std::string msg = check_error(original, changed, dir);
  EXPECT_NE(std::string::npos, msg.find("p.ngc:3")) << msg;
  EXPECT_NE(std::string::npos, msg.find("at line 48 of the new program")) << msg;
}
