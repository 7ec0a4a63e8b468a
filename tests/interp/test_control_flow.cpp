// O-words: subroutines (local parameters, return values, files), if/elseif/
// else, while, do-while, repeat, break, continue.
#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <vector>

#include "interp_test_util.hpp"
#include "test_paths.hpp"

namespace truecut::interp::testing {
namespace {

std::vector<double> xs(const CanonProgram& p) {
  std::vector<double> out;
  for (const auto& c : p.calls)
    if (auto* t = std::get_if<StraightTraverse>(&c.op)) out.push_back(t->end.x);
  return out;
}

TEST(Subroutines, ArgumentsAreLocalAndValuesReturn) {
  auto p =
      run("#1 = 99\n"
          "o100 sub\n  G0 X[#1 + #2]\n  #1 = 0\n  o100 return [#1 + 7]\no100 endsub\n"
          "o100 call [1] [2]\nG0 X#<_value>\nG0 X#1\nM2\n");
  EXPECT_EQ(xs(p), (std::vector<double>{3, 7, 99}));
}

TEST(Subroutines, NamedLocalsAndGlobals) {
  auto p =
      run("#<v> = 1\n#<_g> = 1\n"
          "o<s> sub\n  #<v> = 5\n  #<_g> = 6\n  G0 X#<v>\no<s> endsub [42]\n"
          "o<s> call\nG0 X#<v>\nG0 X#<_g>\nG0 X#<_value>\nM2\n");
  EXPECT_EQ(xs(p), (std::vector<double>{5, 1, 6, 42}));
}

TEST(Subroutines, RecursionAndDefinitionsAreSkipped) {
  auto p =
      run("o<fact> sub\n"
          "  o1 if [#1 LE 1]\n    o<fact> return [1]\n  o1 endif\n"
          "  o<fact> call [#1 - 1]\n  o<fact> return [#<_value> * #1]\n"
          "o<fact> endsub\n"
          "o<fact> call [5]\nG0 X#<_value>\nM2\n");
  EXPECT_EQ(xs(p), (std::vector<double>{120}));
}

TEST(Subroutines, FromAFileBesideTheProgram) {
  const auto dir = truecut::test::scratch_dir();
  std::ofstream(dir / "side.ngc") << "o<side> sub\nG0 X#1\no<side> endsub\nM2\n";
  std::ofstream(dir / "main.ngc") << "o<side> call [4]\nG0 Y1\nM2\n";
  InterpreterOptions o;
  auto p = Interpreter(o).run_file(dir / "main.ngc");
  EXPECT_EQ(xs(p), (std::vector<double>{4, 4}));
  ASSERT_EQ(p.files.size(), 2u);
  bool from_side = false;
  for (const auto& c : p.calls)
    if (std::holds_alternative<StraightTraverse>(c.op) && c.context.file == 1) from_side = true;
  EXPECT_TRUE(from_side) << "calls record the file they come from";
}

// o123 call with no o123 sub in the program loads 123.ngc, as rs274 does.
TEST(Subroutines, NumberedFromAFileBesideTheProgram) {
  const auto dir = truecut::test::scratch_dir();
  std::ofstream(dir / "123.ngc") << "o123 sub\nG0 X#1\no123 endsub\nM2\n";
  std::ofstream(dir / "main.ngc") << "o123 call [7]\nG0 Y1\nM2\n";
  auto p = Interpreter(InterpreterOptions{}).run_file(dir / "main.ngc");
  EXPECT_EQ(xs(p), (std::vector<double>{7, 7}));
  ASSERT_EQ(p.files.size(), 2u);
}

// A folder or a pipe where the subroutine file would be was "unknown
// subroutine" (a pipe could have blocked the reader): named for what it is.
TEST(Subroutines, AFileThatIsNotARegularFileIsNamedForWhatItIs) {
  const auto dir = truecut::test::scratch_dir();
  std::filesystem::create_directory(dir / "sub.ngc");
  std::ofstream(dir / "main.ngc") << "o<sub> call\nM2\n";
  try {
    Interpreter(InterpreterOptions{}).run_file(dir / "main.ngc");
    ADD_FAILURE();
  } catch (const GcodeError& e) {
    EXPECT_NE(std::string(e.what()).find("sub.ngc is not a regular file (a folder, device or "
                                         "pipe), so it cannot hold o<sub> sub"),
              std::string::npos)
        << e.what();
  }
}

TEST(ControlFlow, IfElseifElse) {
  const std::string sub =
      "o<c> sub\n o10 if [#1 GT 5]\n  G0 X3\n o10 elseif [#1 GT 2]\n  G0 X2\n"
      " o10 else\n  G0 X1\n o10 endif\no<c> endsub\n";
  EXPECT_EQ(xs(run(sub + "o<c> call [9]\no<c> call [3]\no<c> call [0]\nM2\n")),
            (std::vector<double>{3, 2, 1}));
}

TEST(ControlFlow, Loops) {
  auto w = run("#1 = 0\no1 while [#1 LT 3]\n G0 X#1\n #1 = [#1 + 1]\no1 endwhile\nM2\n");
  EXPECT_EQ(xs(w), (std::vector<double>{0, 1, 2}));
  auto r =
      run("o2 repeat [3]\n G91 G0 X2\no2 endrepeat\no3 repeat [0]\n G0 X99\no3 endrepeat\nM2\n");
  EXPECT_EQ(xs(r), (std::vector<double>{2, 4, 6}));
  auto d = run("#1 = 0\no4 do\n G0 X#1\n #1 = [#1 + 1]\no4 while [#1 LT 0]\nM2\n");
  EXPECT_EQ(xs(d), (std::vector<double>{0})) << "a do loop runs at least once";
}

TEST(ControlFlow, BreakAndContinue) {
  auto b =
      run("#1 = 0\no1 while [1]\n #1 = [#1 + 1]\n o2 if [#1 GT 3]\n  o1 break\n o2 endif\n"
          " o3 if [#1 EQ 2]\n  o1 continue\n o3 endif\n G0 X#1\no1 endwhile\nM2\n");
  EXPECT_EQ(xs(b), (std::vector<double>{1, 3}));
  auto r =
      run("#1 = 0\no5 repeat [4]\n #1 = [#1 + 1]\n o6 if [#1 EQ 2]\n  o5 continue\n"
          " o6 endif\n G0 X#1\no5 endrepeat\nM2\n");
  EXPECT_EQ(xs(r), (std::vector<double>{1, 3, 4}));
}

TEST(ControlFlow, RunawayLoopIsStopped) {
  InterpreterOptions o;
  o.max_blocks = 1000;
  auto e = error_of("o1 while [1]\n G0 X1\no1 endwhile\nM2\n", o);
  EXPECT_NE(e.message().find("endless loop"), std::string::npos);
}

TEST(ControlFlow, ProgressIsReportedEveryNBlocks) {
  // A loop of 3 blocks run 100 times plus the program's own blocks: the
  // callback sees every 50th block, counting loops and subroutines too.
  InterpreterOptions o;
  std::vector<std::int64_t> seen;
  o.progress = [&](std::int64_t blocks) { seen.push_back(blocks); };
  o.progress_every_blocks = 50;
  Interpreter(o).run_text(
      "#1 = 0\no1 while [#1 LT 100]\n G0 X#1\n #1 = [#1 + 1]\no1 endwhile\nM2\n", "p.ngc");
  ASSERT_GE(seen.size(), 6u);
  for (std::size_t i = 0; i < seen.size(); ++i)
    EXPECT_EQ(std::int64_t(50 * (i + 1)), seen[i]);
}

TEST(ControlFlow, Errors) {
  EXPECT_NE(error_of("o9 call\nM2\n").message().find("unknown subroutine"), std::string::npos);
  EXPECT_NO_THROW(run("o1 if [1]\nG0 X1\nM2\n"));  // like LinuxCNC: endif is only searched for
  auto e = error_of("o1 if [0]\nG0 X1\nM2\n");
  EXPECT_NE(e.message().find("no matching o1"), std::string::npos);
  EXPECT_NE(error_of("o1 endwhile\nM2\n").message().find("without while"), std::string::npos);
  EXPECT_NE(error_of("o1 frobnicate\nM2\n").message().find("unknown O-word"), std::string::npos);
  EXPECT_NE(error_of("o1 sub\nG0 X1\n").message().find("no matching o1 endsub"), std::string::npos);
  EXPECT_NE(error_of("o<r> sub\no<r> call\no<r> endsub\no<r> call\nM2\n").message().find("deep"),
            std::string::npos);
}

}  // namespace
}  // namespace truecut::interp::testing
