// Modal groups and the settings words: plane, units, path control, feed
// mode, spindle, coolant, tools and tool length offsets, stops and the end.
#include <gtest/gtest.h>

#include <algorithm>

#include "interp_test_util.hpp"

namespace truecut::interp::testing {
namespace {

TEST(Modal, StartUpCallsLikeRs274) {
  auto p = run("M2\n");
  std::vector<std::string> all;
  for (const auto& c : p.calls)
    all.push_back(format_rs274(c.op));
  ASSERT_GE(all.size(), 6u);
  EXPECT_EQ(all[0], "USE_LENGTH_UNITS(CANON_UNITS_MM)");
  EXPECT_EQ(all[1], "SET_G5X_OFFSET(1, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)");
  EXPECT_EQ(all[5], "ON_RESET()");
}

TEST(Modal, PlaneUnitsAndPathControl) {
  auto p = run("G18\nG20\nG21\nG61\nG61.1\nG64\nG64 P0.05\nG64 P0.1 Q0.02\nM2\n");
  EXPECT_EQ(calls(p)[0], "SELECT_PLANE(CANON_PLANE_XZ)");
  EXPECT_EQ(calls(p)[1], "USE_LENGTH_UNITS(CANON_UNITS_INCHES)");
  EXPECT_EQ(
      calls_named(p, {"SET_MOTION_CONTROL_MODE", "SET_NAIVECAM_TOLERANCE"}),
      (std::vector<std::string>{
          "SET_MOTION_CONTROL_MODE(CANON_EXACT_PATH)", "SET_MOTION_CONTROL_MODE(CANON_EXACT_STOP)",
          "SET_MOTION_CONTROL_MODE(CANON_CONTINUOUS, 0.000000)", "SET_NAIVECAM_TOLERANCE(0.0000)",
          "SET_MOTION_CONTROL_MODE(CANON_CONTINUOUS, 0.050000)", "SET_NAIVECAM_TOLERANCE(0.0500)",
          "SET_MOTION_CONTROL_MODE(CANON_CONTINUOUS, 0.100000)",
          "SET_NAIVECAM_TOLERANCE(0.0200)"}));
}

TEST(Modal, InchProgramsPrintInches) {
  auto p = run("G0 X25.4\nG20\nG0 Y1\nM2\n");
  EXPECT_EQ(moves(p)[1], "STRAIGHT_TRAVERSE(1.0000, 1.0000, 0.0000, 0.0000, 0.0000, 0.0000)");
  EXPECT_EQ(p.calls.back().context.units, LengthUnits::kInch) << "M2 does not change units";
}

TEST(Modal, FeedModeSwitchResetsTheFeed) {
  auto e = error_of("F100\nG94\nG1 X1\nM2\n");
  EXPECT_EQ(e.where().line, 3);
  EXPECT_NE(e.message().find("zero feed rate"), std::string::npos);
}

TEST(Modal, SpindleCoolantAndStops) {
  auto p = run("S1000 M3\nM4\nM5\nM7\nM8\nM9\nM0\nM1\nG4 P1.5\nM2\n");
  EXPECT_EQ(calls(p), (std::vector<std::string>{
                          "SET_SPINDLE_SPEED(0, 1000.0000)",
                          "START_SPINDLE_CLOCKWISE(0)",
                          "START_SPINDLE_COUNTERCLOCKWISE(0)",
                          "STOP_SPINDLE_TURNING(0)",
                          "MIST_ON()",
                          "FLOOD_ON()",
                          "MIST_OFF()",
                          "FLOOD_OFF()",
                          "PROGRAM_STOP()",
                          "OPTIONAL_PROGRAM_STOP()",
                          "DWELL(1.5000)",
                          "SET_G5X_OFFSET(1, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
                          "SET_XY_ROTATION(0.0000)",
                          "SET_FEED_MODE(0, 0)",
                          "SET_FEED_RATE(0.0000)",
                          "STOP_SPINDLE_TURNING(0)",
                          "SET_SPINDLE_MODE(0 0.0000)",
                          "PROGRAM_END()",
                          "ON_RESET()",
                          "ON_RESET()"}));
}

TEST(Modal, M30AddsPalletShuttleAndM2ResetsPlane) {
  auto p = run("G18 M8\nM30\n");
  auto c = calls(p);
  EXPECT_NE(std::find(c.begin(), c.end(), "SELECT_PLANE(CANON_PLANE_XY)"), c.end());
  EXPECT_NE(std::find(c.begin(), c.end(), "FLOOD_OFF()"), c.end());
  EXPECT_NE(std::find(c.begin(), c.end(), "PALLET_SHUTTLE()"), c.end());
}

// M70 saves, M72 restores only what differs (units first, then the rest in
// the order of a block), M73 restores when its subroutine returns; the
// motion mode is not part of the state.
TEST(ModalState, RestoreEmitsOnlyTheDifferencesInLinuxCncOrder) {
  auto p =
      run("G64 P0.01 F100 S1000 M3 M8\nG1 X1\nM70\n"
          "G20 G18 G91 G61 G55 G98 M4 S500 M7 F3\nG0 X1\nM72\nX2\nM2\n");
  const auto c = calls(p);
  // G0 X1 under G91 G20: 1 mm + 1 inch.
  const auto m72 = std::find(c.begin(), c.end(),
                             "STRAIGHT_TRAVERSE(1.0394, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)");
  ASSERT_NE(m72, c.end());
  const std::vector<std::string> restored(m72 + 1, m72 + 13);
  EXPECT_EQ(restored,
            (std::vector<std::string>{
                "USE_LENGTH_UNITS(CANON_UNITS_MM)", "SET_FEED_RATE(100.0000)",
                "SET_SPINDLE_SPEED(0, 1000.0000)", "START_SPINDLE_CLOCKWISE(0)",
                "SELECT_PLANE(CANON_PLANE_XY)",
                "SET_G5X_OFFSET(1, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
                "SET_G92_OFFSET(0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
                "SET_XY_ROTATION(0.0000)", "SET_MOTION_CONTROL_MODE(CANON_CONTINUOUS, 0.010000)",
                "SET_NAIVECAM_TOLERANCE(0.0100)",
                "COMMENT(\"interpreter: distance mode changed to absolute\")",
                "COMMENT(\"interpreter: retract mode set to r_plane\")"}));
  // The mist stays on (the saved state had flood only), G0 stays the motion.
  EXPECT_EQ(*(m72 + 13), "STRAIGHT_TRAVERSE(2.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)");
  // Nothing differs: nothing is emitted.
  auto same = run("M70\nM72\nM2\n");
  auto plain = run("M2\n");
  EXPECT_EQ(calls(same), calls(plain));
}

TEST(ModalState, M73RestoresWhenTheSubroutineReturns) {
  auto p =
      run("o1 sub\nM73\nG20 G91 M3 S10 F3\no2 if [1]\no1 return\no2 endif\nG18\n"
          "o1 endsub\no1 call\nG0 X1\nM2\n");
  const auto c = calls(p);
  const std::vector<std::string> expected = {
      "SET_FEED_RATE(3.0000)",
      "SET_SPINDLE_SPEED(0, 10.0000)",
      "START_SPINDLE_CLOCKWISE(0)",
      "USE_LENGTH_UNITS(CANON_UNITS_INCHES)",
      "COMMENT(\"interpreter: distance mode changed to incremental\")",
      "USE_LENGTH_UNITS(CANON_UNITS_MM)",
      "SET_FEED_RATE(0.0000)",
      "SET_SPINDLE_SPEED(0, 0.0000)",
      "STOP_SPINDLE_TURNING(0)",
      "COMMENT(\"interpreter: distance mode changed to absolute\")",
      "STRAIGHT_TRAVERSE(1.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)"};
  ASSERT_GE(c.size(), expected.size());
  EXPECT_EQ(std::vector<std::string>(c.begin(), c.begin() + expected.size()), expected);
  // M71 forgets: no restore on return.
  auto forgotten = run("o1 sub\nM73\nG20\nM71\no1 endsub\no1 call\nG0 X1\nM2\n");
  EXPECT_EQ(calls_named(forgotten, {"USE_LENGTH_UNITS"}),
            (std::vector<std::string>{"USE_LENGTH_UNITS(CANON_UNITS_INCHES)"}));
}

TEST(Tools, ToolChangeUsesTheTableRow) {
  auto p = run("T7 M6\nG43\nG0 Z0\nM2\n");
  EXPECT_EQ(calls(p)[0], "SELECT_TOOL(7)");
  EXPECT_EQ(calls(p)[3], "CHANGE_TOOL(3)");
  EXPECT_EQ(calls(p)[4],
            "USE_TOOL_LENGTH_OFFSET(0.0000 0.0000 -5.0000, 0.0000 0.0000 0.0000, 0.0000 0.0000 "
            "0.0000)");
  EXPECT_EQ(p.calls.back().context.tool, 7);
}

TEST(Tools, LengthOffsetShiftsTheProgramPosition) {
  // Without a tool change on the line the position is not re-read.
  auto p = run("G0 Z0\nG43 H2\nG0 X1\nG49\nG0 Y1\nM2\n");
  auto m = moves(p);
  EXPECT_EQ(m[1], "STRAIGHT_TRAVERSE(1.0000, 0.0000, -20.0000, 0.0000, 0.0000, 0.0000)");
  // T2 also offsets X by 1 mm: after G49 the tool is at program X 2.
  EXPECT_EQ(m[2], "STRAIGHT_TRAVERSE(2.0000, 1.0000, 0.0000, 0.0000, 0.0000, 0.0000)");
}

TEST(Tools, ToolChangeRereadsThePosition) {
  // LinuxCNC re-synchronises after M6: the last programmed numbers stay.
  auto p = run("G0 Z0\nT2 M6 G43 H2\nG0 X1\nM2\n");
  EXPECT_EQ(moves(p)[1], "STRAIGHT_TRAVERSE(1.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)");
}

TEST(Tools, M61SetsTheToolWithoutAChange) {
  auto p = run("M61 Q2\nM2\n");
  EXPECT_EQ(calls(p)[0], "CHANGE_TOOL_NUMBER(2)");
}

TEST(Comments, OnlyTheLastParenthesizedCommentIsACall) {
  auto p = run("G0 X1 (first) (  second)\n; dropped\n(MSG, Check clamps)\n(DEBUG, x=#<_x>)\nM2\n");
  EXPECT_EQ(calls_named(p, {"COMMENT", "MESSAGE"}),
            (std::vector<std::string>{"COMMENT(\"second\")", "MESSAGE(\" Check clamps\")",
                                      "MESSAGE(\" x=1.000000\")"}));
}

TEST(Lines, BlockDeleteSwitch) {
  const std::string text = "G0 X1\n/G0 X2\nM2\n";
  EXPECT_EQ(moves(run(text)).size(), 2u);
  InterpreterOptions o;
  o.block_delete = true;
  EXPECT_EQ(moves(run(text, o)).size(), 1u);
}

TEST(Lines, LineNumbersCaseAndBlanks) {
  auto p = run("N10 g0 x 1 . 5 y2\nn20G1X3F100\nM2\n");
  EXPECT_EQ(moves(p), (std::vector<std::string>{
                          "STRAIGHT_TRAVERSE(1.5000, 2.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
                          "STRAIGHT_FEED(3.0000, 2.0000, 0.0000, 0.0000, 0.0000, 0.0000)"}));
  EXPECT_EQ(p.calls.back().context.line, 3);
}

TEST(Lines, PercentFramedProgram) {
  auto p = run("%\nG0 X1\n%\nG0 X2\n");
  EXPECT_EQ(moves(p).size(), 1u);
  EXPECT_EQ(calls(p)[1], "FINISH()");
}

TEST(Axes, BIsRejectedOnTheACMachineUnlessEnabled) {
  auto e = error_of("G0 X1 B10\nM2\n");
  EXPECT_EQ(e.where().column, 7);
  EXPECT_NE(e.message().find("B axis"), std::string::npos);
  InterpreterOptions o;
  o.has_b = true;
  EXPECT_EQ(moves(run("G0 X1 B10\nM2\n", o))[0],
            "STRAIGHT_TRAVERSE(1.0000, 0.0000, 0.0000, 0.0000, 10.0000, 0.0000)");
}

}  // namespace
}  // namespace truecut::interp::testing
