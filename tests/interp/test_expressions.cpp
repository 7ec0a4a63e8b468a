// Parameters and expressions: operators, precedence, functions, named and
// numbered parameters, LinuxCNC's "set after the line" rule.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "interp_test_util.hpp"

namespace truecut::interp::testing {
namespace {

// X of the traverse "G0 X<expr>" after `setup`.
double eval(const std::string& expr, const std::string& setup = "") {
  auto p = run(setup + "G0 X" + expr + "\nM2\n");
  double x = 0;
  bool found = false;
  for (const auto& c : p.calls)
    if (auto* t = std::get_if<StraightTraverse>(&c.op)) x = t->end.x, found = true;
  EXPECT_TRUE(found) << "no traverse";
  return x;
}

TEST(Expressions, ArithmeticAndPrecedence) {
  EXPECT_DOUBLE_EQ(eval("[1 + 2 * 3]"), 7);
  EXPECT_DOUBLE_EQ(eval("[[1 + 2] * 3]"), 9);
  EXPECT_DOUBLE_EQ(eval("[2 ** 3 * 2]"), 16);
  EXPECT_DOUBLE_EQ(eval("[10 - 4 - 3]"), 3);  // left associative
  EXPECT_DOUBLE_EQ(eval("[12 / 3 / 2]"), 2);
  EXPECT_DOUBLE_EQ(eval("[-2 ** 2]"), 4);  // the sign belongs to the number
  EXPECT_DOUBLE_EQ(eval("[1 + 2 GT 2]"), 1);
  EXPECT_DOUBLE_EQ(eval("[1 GT 2 OR 3 LT 4]"), 1);
}

TEST(Expressions, ModTakesTheSignOfTheDivisor) {
  EXPECT_DOUBLE_EQ(eval("[10 MOD 3]"), 1);
  EXPECT_DOUBLE_EQ(eval("[-7 MOD 3]"), 2);
}

TEST(Expressions, ComparisonsAndLogic) {
  EXPECT_DOUBLE_EQ(eval("[1 EQ 1.00001]"), 1);  // EQ has a 1e-4 tolerance
  EXPECT_DOUBLE_EQ(eval("[1 EQ 1.001]"), 0);
  EXPECT_DOUBLE_EQ(eval("[1 NE 2]"), 1);
  EXPECT_DOUBLE_EQ(eval("[2 GE 2]"), 1);
  EXPECT_DOUBLE_EQ(eval("[2 LE 1]"), 0);
  EXPECT_DOUBLE_EQ(eval("[5 AND 0]"), 0);
  EXPECT_DOUBLE_EQ(eval("[3 XOR 0]"), 1);
  EXPECT_DOUBLE_EQ(eval("[3 XOR 1]"), 0);
}

TEST(Expressions, FunctionsWorkInDegrees) {
  EXPECT_NEAR(eval("[SIN[30]]"), 0.5, 1e-12);
  EXPECT_NEAR(eval("[COS[60]]"), 0.5, 1e-12);
  EXPECT_NEAR(eval("[TAN[45]]"), 1.0, 1e-12);
  EXPECT_NEAR(eval("[ASIN[1]]"), 90, 1e-12);
  EXPECT_NEAR(eval("[ACOS[0]]"), 90, 1e-12);
  EXPECT_NEAR(eval("[ATAN[1]/[-1]]"), 135, 1e-12);
  EXPECT_DOUBLE_EQ(eval("[ABS[-3]]"), 3);
  EXPECT_DOUBLE_EQ(eval("[SQRT[16]]"), 4);
  EXPECT_NEAR(eval("[EXP[1]]"), 2.718281828459045, 1e-12);
  EXPECT_NEAR(eval("[LN[10]]"), 2.302585092994046, 1e-12);
  EXPECT_DOUBLE_EQ(eval("[FIX[-2.5]]"), -3);
  EXPECT_DOUBLE_EQ(eval("[FUP[2.1]]"), 3);
  EXPECT_DOUBLE_EQ(eval("[ROUND[2.5]]"), 3);
  EXPECT_DOUBLE_EQ(eval("[ROUND[-2.5]]"), -3);
}

TEST(Expressions, NumberForms) {
  EXPECT_DOUBLE_EQ(eval(".5"), 0.5);
  EXPECT_DOUBLE_EQ(eval("-3."), -3);
  EXPECT_DOUBLE_EQ(eval("+ 1 2 . 5"), 12.5);  // blanks are removed first
  EXPECT_DOUBLE_EQ(eval("-[1 + 1]"), -2);
}

TEST(Parameters, NumberedNamedIndirect) {
  EXPECT_DOUBLE_EQ(eval("#1", "#1 = 4\n"), 4);
  EXPECT_DOUBLE_EQ(eval("##2", "#1 = 4\n#2 = 1\n"), 4);
  EXPECT_DOUBLE_EQ(eval("#[#2 + 1]", "#3 = 8\n#2 = 2\n"), 8);
  EXPECT_DOUBLE_EQ(eval("#<Depth>", "#<depth> = -2\n"), -2);  // names ignore case
  EXPECT_DOUBLE_EQ(eval("#<_g>", "#<_g> = 6\n"), 6);
  EXPECT_DOUBLE_EQ(eval("[EXISTS[#<d>] + 2 * EXISTS[#<e>]]", "#<d> = 1\n"), 1);
  EXPECT_DOUBLE_EQ(eval("#99"), 0);  // unset numbered parameters read 0
}

TEST(Parameters, SettingsTakeEffectAfterTheLine) {
  // #2 sees the old #1; the move sees the old #3.
  EXPECT_DOUBLE_EQ(eval("#2", "#1 = 2 #2 = [#1 + 1]\n"), 1);
  EXPECT_DOUBLE_EQ(eval("#3", "#3 = 15\n#3 = 6\n"), 6);
  auto p = run("#3 = 15\n#3 = 6 G0 X#3\nM2\n");
  EXPECT_EQ(moves(p)[0], "STRAIGHT_TRAVERSE(15.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)");
}

TEST(Parameters, PredefinedReadOnlyNames) {
  EXPECT_DOUBLE_EQ(eval("[#<_x> + 1]", "G0 X5\n"), 6);
  EXPECT_DOUBLE_EQ(eval("#<_metric>"), 1);
  EXPECT_DOUBLE_EQ(eval("#<_imperial>", "G20\n"), 1);
  EXPECT_DOUBLE_EQ(eval("#<_coord_system>", "G55\n"), 550);
  EXPECT_DOUBLE_EQ(eval("#5220", "G56\n"), 3);
  auto y = run("G0 Y7\nG0 X#5421\nM2\n");
  EXPECT_EQ(moves(y)[1], "STRAIGHT_TRAVERSE(7.0000, 7.0000, 0.0000, 0.0000, 0.0000, 0.0000)");
  auto e = error_of("#<_x> = 3\nM2\n");
  EXPECT_NE(e.message().find("read-only"), std::string::npos) << e.what();
}

TEST(Expressions, Errors) {
  auto e = error_of("G0 X[1 / [2 - 2]]\nM2\n");
  EXPECT_EQ(e.where().column, 8);
  EXPECT_EQ(e.message(), "division by zero");
  EXPECT_EQ(error_of("G0 X[5 MOD 0]\nM2\n").where().column, 8);
  auto b = error_of("G0 X[1 + [2 * 3]\nM2\n");
  EXPECT_EQ(b.where().column, 5);
  EXPECT_NE(b.message().find("unbalanced brackets"), std::string::npos);
  auto c = error_of("G0 X[1 + 2]]\nM2\n");
  EXPECT_EQ(c.where().column, 12);
  EXPECT_NE(c.message().find("unbalanced brackets"), std::string::npos);
  EXPECT_NE(error_of("G0 X[SQRT[-1]]\nM2\n").message().find("SQRT"), std::string::npos);
  EXPECT_NE(error_of("G0 X[LN[0]]\nM2\n").message().find("LN"), std::string::npos);
  EXPECT_NE(error_of("G0 X[ASIN[2]]\nM2\n").message().find("ASIN"), std::string::npos);
  EXPECT_NE(error_of("G0 X[-8 ** 0.5]\nM2\n").message().find("negative"), std::string::npos);
  EXPECT_NE(error_of("G0 X#<nope>\nM2\n").message().find("not defined"), std::string::npos);
  EXPECT_NE(error_of("G0 X#6000\nM2\n").message().find("out of range"), std::string::npos);
  EXPECT_NE(error_of("G0 X[1 $ 2]\nM2\n").message().find("operator"), std::string::npos);
}

// Hostile input (issue 23): a nesting that used to overflow the stack, and
// results that used to reach the canon output as inf.
TEST(Expressions, NestingDeeperThanTheLimitIsRefusedAtTheBracket) {
  constexpr int kMaxExpressionNesting = 1000;  // docs/gcode.md, "Limits"
  const int deep = 50000;
  const auto e =
      error_of("G0 X" + std::string(deep, '[') + "1" + std::string(deep, ']') + "\nM2\n");
  EXPECT_EQ(1, e.where().line);
  EXPECT_EQ(4 + kMaxExpressionNesting + 1, e.where().column);  // "G0 X" then the 1001st '['
  EXPECT_NE(std::string::npos, e.message().find("nested deeper than 1000")) << e.message();
  // At the limit itself the expression is read.
  const int limit = kMaxExpressionNesting;
  EXPECT_DOUBLE_EQ(2, eval(std::string(limit, '[') + "2" + std::string(limit, ']')));
}

// Found by fuzz_expression (2026-12-02): a chain of 4000 '#' (each reads the
// number of the next parameter) overflowed the stack; it counts against the
// bracket limit now, and so does a chain that mixes both.
TEST(Expressions, AParameterChainDeeperThanTheLimitIsRefusedAtItsHash) {
  constexpr int kMaxExpressionNesting = 1000;  // docs/gcode.md, "Limits"
  const auto e = error_of("G0 X" + std::string(50000, '#') + "1\nM2\n");
  EXPECT_EQ(1, e.where().line);
  EXPECT_EQ(4 + kMaxExpressionNesting + 1, e.where().column);  // the 1001st '#'
  EXPECT_NE(std::string::npos, e.message().find("nested deeper than 1000")) << e.message();
  std::string mixed;
  for (int i = 0; i < 20000; ++i)
    mixed += i % 2 ? "[" : "#";
  const auto m = error_of("G0 X" + mixed + "1\nM2\n");
  EXPECT_EQ(4 + kMaxExpressionNesting + 1, m.where().column) << m.message();
  // At the limit the chain is read: #1 = 1, so every #...#1 is 1.
  EXPECT_DOUBLE_EQ(1, eval(std::string(kMaxExpressionNesting, '#') + "1", "#1 = 1\n"));
}

TEST(Expressions, OverflowIsRefusedWhereItArises) {
  struct Case {
    const char* program;
    int column;
    const char* says;
  };
  for (const Case& c :
       {Case{"G0 X[10 ** 400]\nM2\n", 9, "the operator ** overflows"},
        Case{"G0 X[EXP[1000]]\nM2\n", 6, "EXP overflows"},
        Case{"#1 = [10 ** 200]\nG0 X[#1 * #1]\nM2\n", 9, "the operator * overflows"}}) {
    const auto e = error_of(c.program);
    EXPECT_EQ(c.column, e.where().column) << c.program;
    EXPECT_NE(std::string::npos, e.message().find(c.says)) << e.message();
    EXPECT_NE(std::string::npos, e.message().find("not a finite number")) << e.message();
  }
  const std::string huge = "1" + std::string(400, '0');
  const auto e = error_of("G0 X" + huge + "\nM2\n");
  EXPECT_EQ(5, e.where().column);
  EXPECT_NE(std::string::npos, e.message().find("this number (401 characters) overflows"))
      << e.message();
  // The largest values that stay finite are still read.
  EXPECT_DOUBLE_EQ(std::pow(10.0, 300), eval("[10 ** 300]"));
  EXPECT_DOUBLE_EQ(std::exp(700.0), eval("[EXP[700]]"));
}

}  // namespace
}  // namespace truecut::interp::testing
