// Work offsets: G54..G59.3, G10 L2/L20, G92 family, G53, G28/G30.
#include <gtest/gtest.h>

#include "interp_test_util.hpp"

namespace truecut::interp::testing {
namespace {

TEST(Offsets, SelectingACoordinateSystem) {
  auto p = run("G10 L2 P2 X100 Y20 A10\nG55\nG0 X1 Y1 A0\nG55\nM2\n");
  EXPECT_EQ(calls(p), (std::vector<std::string>{
                          "COMMENT(\"interpreter: setting coordinate system origin\")",
                          "SET_G5X_OFFSET(2, 100.0000, 20.0000, 0.0000, 10.0000, 0.0000, 0.0000)",
                          "SET_G92_OFFSET(0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
                          "SET_XY_ROTATION(0.0000)",
                          "STRAIGHT_TRAVERSE(1.0000, 1.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
                          "COMMENT(\"interpreter: continuing to use same coordinate system\")",
                          "SET_G5X_OFFSET(1, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
                          "SET_XY_ROTATION(0.0000)", "SET_FEED_MODE(0, 0)", "SET_FEED_RATE(0.0000)",
                          "STOP_SPINDLE_TURNING(0)", "SET_SPINDLE_MODE(0 0.0000)", "PROGRAM_END()",
                          "ON_RESET()", "ON_RESET()"}));
  EXPECT_NEAR(p.calls[10].context.g5x_mm.x, 100, 1e-12);
}

TEST(Offsets, AllNineSystems) {
  const char* codes[] = {"G54", "G55", "G56", "G57", "G58", "G59", "G59.1", "G59.2", "G59.3"};
  for (int n = 1; n <= 9; ++n) {
    const std::string text = "G10 L2 P" + std::to_string(n) + " X" + std::to_string(n) + "\nG55\n" +
                             codes[n - 1] + "\nG0 X0\n#1 = #5220\nG0 Y#1\nM2\n";
    auto p = run(text);
    for (const auto& c : p.calls)
      if (std::holds_alternative<StraightTraverse>(c.op)) {
        EXPECT_NEAR(c.context.g5x_mm.x, n, 1e-12) << codes[n - 1];
      }
    auto m = moves(p);
    EXPECT_EQ(m.back(), "STRAIGHT_TRAVERSE(0.0000, " + std::to_string(n) +
                            ".0000, 0.0000, 0.0000, 0.0000, 0.0000)");
  }
}

TEST(Offsets, G10L20MakesTheCurrentPointTheGivenValue) {
  auto p = run("G0 X7 Y3\nG10 L20 P1 X0 Y1\nG0 X1\nM2\n");
  auto c = calls(p);
  EXPECT_EQ(c[1], "SET_G5X_OFFSET(1, 7.0000, 2.0000, 0.0000, 0.0000, 0.0000, 0.0000)");
  EXPECT_EQ(moves(p)[1], "STRAIGHT_TRAVERSE(1.0000, 1.0000, 0.0000, 0.0000, 0.0000, 0.0000)");
}

TEST(Offsets, G92Family) {
  auto p = run("G0 X5\nG92 X0\nG0 X1\nG92.2\nG0 Y1\nG92.3\nG0 Y2\nG92.1\nG0 Y3\nM2\n");
  EXPECT_EQ(
      calls_named(p, {"SET_G92_OFFSET"}),
      (std::vector<std::string>{"SET_G92_OFFSET(5.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
                                "SET_G92_OFFSET(0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
                                "SET_G92_OFFSET(5.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
                                "SET_G92_OFFSET(0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)"}));
  auto m = moves(p);
  EXPECT_EQ(m[1], "STRAIGHT_TRAVERSE(1.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)");
  EXPECT_EQ(m[2], "STRAIGHT_TRAVERSE(6.0000, 1.0000, 0.0000, 0.0000, 0.0000, 0.0000)");
  EXPECT_EQ(m[3], "STRAIGHT_TRAVERSE(1.0000, 2.0000, 0.0000, 0.0000, 0.0000, 0.0000)");
}

TEST(Offsets, G53MovesInMachineCoordinates) {
  auto p = run("G10 L2 P1 Z-50\nG54\nT1 M6 G43\nG53 G0 Z0\nG53 G1 X10 F100\nM2\n");
  auto m = moves(p);
  // Machine Z 0 = program Z - (-50) + 10 (tool).
  EXPECT_EQ(m[0], "STRAIGHT_TRAVERSE(0.0000, 0.0000, 40.0000, 0.0000, 0.0000, 0.0000)");
  EXPECT_EQ(m[1], "STRAIGHT_FEED(10.0000, 0.0000, 40.0000, 0.0000, 0.0000, 0.0000)");
  EXPECT_NE(error_of("G91 G53 G0 X0\nM2\n").message().find("incremental"), std::string::npos);
  EXPECT_NE(error_of("G53 G2 X1 I1\nM2\n").message().find("G53"), std::string::npos);
}

TEST(Offsets, G28GoesThroughTheGivenPointToHome) {
  auto p = run("G0 X1 Y2 Z3\nG28.1\nG0 X10 Y10 Z10\nG28 Z20\nG28\nM2\n");
  auto m = moves(p);
  ASSERT_EQ(m.size(), 6u);
  EXPECT_EQ(m[2], "STRAIGHT_TRAVERSE(10.0000, 10.0000, 20.0000, 0.0000, 0.0000, 0.0000)");
  EXPECT_EQ(m[3], "STRAIGHT_TRAVERSE(10.0000, 10.0000, 3.0000, 0.0000, 0.0000, 0.0000)");
  EXPECT_EQ(m[4], "STRAIGHT_TRAVERSE(10.0000, 10.0000, 3.0000, 0.0000, 0.0000, 0.0000)");
  EXPECT_EQ(m[5], "STRAIGHT_TRAVERSE(1.0000, 2.0000, 3.0000, 0.0000, 0.0000, 0.0000)");
}

// G10 L1 edits the interpreter's copy of the tool table: the next G43 takes
// the new length, the table passed in stays as it was for the next run.
TEST(Offsets, G10L1EditsTheToolTableOfThisRun) {
  InterpreterOptions o;
  o.tools = sample_tools();
  const double before = o.tools.find(1)->offset_mm.z;
  auto p = run("T1 M6\nG10 L1 P1 Z25 R3\nG43\nG0 Z0\nM2\n", o);
  EXPECT_EQ(calls_named(p, {"USE_TOOL_LENGTH_OFFSET"}).at(0),
            "USE_TOOL_LENGTH_OFFSET(0.0000 0.0000 25.0000, 0.0000 0.0000 0.0000, 0.0000 0.0000 "
            "0.0000)");
  EXPECT_EQ(o.tools.find(1)->offset_mm.z, before);
  auto again = run("T1 M6\nG43\nG0 Z0\nM2\n", o);
  int traverses = 0;
  for (const auto& c : again.calls)
    if (std::holds_alternative<StraightTraverse>(c.op)) {
      ++traverses;
      EXPECT_NEAR(c.context.tool_offset_mm.z, before, 1e-12);
    }
  EXPECT_EQ(traverses, 1);
}

TEST(Offsets, G10Errors) {
  EXPECT_NE(error_of("G10 L2 X1\nM2\n").message().find("needs P"), std::string::npos);
  EXPECT_NE(error_of("G10 L1 P5 Z1\nM2\n").message().find("not in the tool table"),
            std::string::npos);
  EXPECT_NE(error_of("G10 L20 P1 R30\nM2\n").message().find("G10 L20 does not take R"),
            std::string::npos);
  EXPECT_NO_THROW(run("G10 L2 P1 R0 X1\nM2\n"));
}

// G10 L2 R: the calls stay in the rotated frame (as rs274 prints them, see
// Rs274Oracle.RotatedCoordinateSystemsMatch); the context carries the
// rotation, so machine_position_mm gives G5x + rotation x (program + G92).
TEST(Offsets, RotatedSystemMachinePositions) {
  auto p =
      run("G10 L2 P1 X10 Y5 R90\nG0 X1 Y0 Z2\nG1 X1 Y2 F100\n#1 = #5230\n"
          "G0 X#1\nG53 G0 X0 Y0\nM2\n");
  std::vector<Axes6> machine;
  for (const auto& c : p.calls)
    if (const auto* t = std::get_if<StraightTraverse>(&c.op)) {
      EXPECT_EQ(c.context.xy_rotation_deg, 90);
      machine.push_back(machine_position_mm(t->end, c.context));
    } else if (const auto* f = std::get_if<StraightFeed>(&c.op)) {
      machine.push_back(machine_position_mm(f->end, c.context));
    }
  ASSERT_EQ(machine.size(), 4u);
  // Program (1, 0) turned by 90 degrees is (0, 1); + G5x (10, 5).
  EXPECT_NEAR(machine[0].x, 10, 1e-12);
  EXPECT_NEAR(machine[0].y, 6, 1e-12);
  EXPECT_NEAR(machine[0].z, 2, 1e-12);
  EXPECT_NEAR(machine[1].x, 8, 1e-12);
  EXPECT_NEAR(machine[1].y, 6, 1e-12);
  EXPECT_NEAR(machine[2].y, 95, 1e-12);  // X#5230 = X90
  EXPECT_NEAR(machine[3].x, 0, 1e-12);   // G53: machine coordinates
  EXPECT_NEAR(machine[3].y, 0, 1e-12);
  EXPECT_EQ(moves(p).back(), "STRAIGHT_TRAVERSE(-5.0000, 10.0000, 2.0000, 0.0000, 0.0000, 0.0000)");
}

}  // namespace
}  // namespace truecut::interp::testing
