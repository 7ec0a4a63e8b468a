// Straight moves and arcs: IJK and R forms, full circles, turns, helices,
// the three planes, incremental and absolute centres, inverse-time feed.
#include <gtest/gtest.h>

#include "interp_test_util.hpp"

namespace truecut::interp::testing {
namespace {

TEST(Motion, TraverseAndFeedKeepUnprogrammedAxes) {
  auto p = run("G0 X1 Y2 Z3\nG1 X4 F100\nG1 A10 C20\nM2\n");
  EXPECT_EQ(moves(p), (std::vector<std::string>{
                          "STRAIGHT_TRAVERSE(1.0000, 2.0000, 3.0000, 0.0000, 0.0000, 0.0000)",
                          "STRAIGHT_FEED(4.0000, 2.0000, 3.0000, 0.0000, 0.0000, 0.0000)",
                          "STRAIGHT_FEED(4.0000, 2.0000, 3.0000, 10.0000, 0.0000, 20.0000)"}));
}

// Cutter compensation holds each move until the next one is known
// (docs/gcode.md): M2 sends the held move; a closing '%' drops it, as rs274
// does. Tool T1: D6, radius 3.
TEST(Motion, CutterCompHeldMovesAtTheProgramEnd) {
  const auto m2 = moves(run("G0 X0 Y0\nG41 D1 G1 X10 F100\nG1 Y10\nM2\n"));
  EXPECT_EQ(m2, (std::vector<std::string>{
                    "STRAIGHT_TRAVERSE(0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
                    "STRAIGHT_FEED(7.0000, 3.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
                    "STRAIGHT_FEED(7.0000, 10.0000, 0.0000, 0.0000, 0.0000, 0.0000)"}));
  const auto percent = moves(run("%\nG0 X0 Y0\nG41 D1 G1 X10 F100\nG1 Y10\n%\n"));
  EXPECT_EQ(percent, (std::vector<std::string>(m2.begin(), m2.end() - 1)));
}

TEST(Motion, ModalMotionAndIncrementalDistance) {
  auto p = run("G1 X1 F100\nY2\nG91 X1 Y1\nC-30\nG90 X0\nM2\n");
  EXPECT_EQ(moves(p), (std::vector<std::string>{
                          "STRAIGHT_FEED(1.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
                          "STRAIGHT_FEED(1.0000, 2.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
                          "STRAIGHT_FEED(2.0000, 3.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
                          "STRAIGHT_FEED(2.0000, 3.0000, 0.0000, 0.0000, 0.0000, -30.0000)",
                          "STRAIGHT_FEED(0.0000, 3.0000, 0.0000, 0.0000, 0.0000, -30.0000)"}));
}

TEST(Motion, ExplicitMotionCodeWithoutAxesMovesToWhereTheToolIs) {
  auto p = run("G0 X1\nG1 F10\nM2\n");
  EXPECT_EQ(moves(p).back(), "STRAIGHT_FEED(1.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)");
}

// Polar coordinates, as LinuxCNC's rs274 runs them: G90 about the program
// origin (a missing word keeps the current point's radius or angle), G91
// added to the current point's radius and angle.
TEST(Polar, AbsoluteAboutTheOriginIncrementalAddedToRadiusAndAngle) {
  auto p = run("G0 X10 Y5\nG1 @10 ^30 F100\n@5\n^90\nG91\nG1 @2 ^0\n@2 ^90\n@3\nM2\n");
  EXPECT_EQ(moves(p), (std::vector<std::string>{
                          "STRAIGHT_TRAVERSE(10.0000, 5.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
                          "STRAIGHT_FEED(8.6603, 5.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
                          "STRAIGHT_FEED(4.3301, 2.5000, 0.0000, 0.0000, 0.0000, 0.0000)",
                          "STRAIGHT_FEED(0.0000, 5.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
                          "STRAIGHT_FEED(0.0000, 7.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
                          "STRAIGHT_FEED(-9.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
                          "STRAIGHT_FEED(-12.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)"}));
}

TEST(Polar, ArcsOffsetsAndCannedCycles) {
  // An arc to a polar end; the origin of a G92-shifted program.
  auto p = run("G0 @10 ^45 Z3\nG2 @10 ^0 R10 F10\nG0 X3 Y4\nG92 X0 Y0\nG0 @1 ^0\nM2\n");
  auto m = moves(p);
  ASSERT_EQ(m.size(), 4u);
  EXPECT_EQ(m[0], "STRAIGHT_TRAVERSE(7.0711, 7.0711, 3.0000, 0.0000, 0.0000, 0.0000)");
  EXPECT_EQ(m[1], "ARC_FEED(10.0000, 0.0000, 0.0000, -0.0000, -1, 3.0000, 0.0000, 0.0000, 0.0000)");
  EXPECT_EQ(m[3], "STRAIGHT_TRAVERSE(1.0000, 0.0000, 3.0000, 0.0000, 0.0000, 0.0000)");
  // G91 canned cycle: each repeat turns the last hole by ^ about the origin.
  auto c = run("G0 X3 Y4 Z2\nG91 G81 ^90 R1 Z-1 L2 F10\nM2\n");
  auto holes = calls_named(c, {"STRAIGHT_FEED"});
  EXPECT_EQ(holes, (std::vector<std::string>{
                       "STRAIGHT_FEED(-4.0000, 3.0000, 2.0000, 0.0000, 0.0000, 0.0000)",
                       "STRAIGHT_FEED(-3.0000, -4.0000, 2.0000, 0.0000, 0.0000, 0.0000)"}));
}

TEST(Arcs, CentreFormInXY) {
  auto p = run("F100\nG2 X10 Y10 I10 J0\nG3 X0 Y20 I-10 J0\nM2\n");
  EXPECT_EQ(moves(p), (std::vector<std::string>{
                          "ARC_FEED(10.0000, 10.0000, 10.0000, 0.0000, -1, 0.0000, 0.0000, "
                          "0.0000, 0.0000)",
                          "ARC_FEED(0.0000, 20.0000, 0.0000, 10.0000, 1, 0.0000, 0.0000, 0.0000, "
                          "0.0000)"}));
}

TEST(Arcs, RadiusFormShortAndLongWay) {
  auto p = run("F100\nG2 X10 Y0 R5\nG0 X0 Y0\nG2 X10 Y10 R10\nG0 X0 Y0\nG2 X10 Y10 R-10\nM2\n");
  auto m = moves(p);
  const ArcFeed* half = nullptr;
  for (const auto& c : p.calls)
    if (!half) half = std::get_if<ArcFeed>(&c.op);
  ASSERT_TRUE(half);
  EXPECT_NEAR(half->center.x, 5.0, 1e-12);
  EXPECT_NEAR(half->center.y, 0.0, 1e-12);
  EXPECT_EQ(half->rotation, -1);
  // Clockwise from (0,0) to (10,10): the short way has its centre at (10,0).
  EXPECT_EQ(m[2],
            "ARC_FEED(10.0000, 10.0000, 10.0000, 0.0000, -1, 0.0000, 0.0000, 0.0000, 0.0000)");
  EXPECT_EQ(m[4],
            "ARC_FEED(10.0000, 10.0000, 0.0000, 10.0000, -1, 0.0000, 0.0000, 0.0000, 0.0000)");
}

TEST(Arcs, FullCirclesTurnsAndHelix) {
  auto p = run("F100\nG2 I5\nG3 X0 Y0 I5 J0 Z-2\nG2 X0 Y0 I5 Z-4 P3\nM2\n");
  auto m = moves(p);
  EXPECT_EQ(m[0], "ARC_FEED(0.0000, 0.0000, 5.0000, 0.0000, -1, 0.0000, 0.0000, 0.0000, 0.0000)");
  EXPECT_EQ(m[1], "ARC_FEED(0.0000, 0.0000, 5.0000, 0.0000, 1, -2.0000, 0.0000, 0.0000, 0.0000)");
  EXPECT_EQ(m[2], "ARC_FEED(0.0000, 0.0000, 5.0000, 0.0000, -3, -4.0000, 0.0000, 0.0000, 0.0000)");
}

TEST(Arcs, OtherPlanesUseLinuxCncAxisOrder) {
  // XZ: first = Z, second = X, axis = Y.  YZ: first = Y, second = Z, axis = X.
  auto p = run("F100\nG18 G2 X10 Z0 I5 K0\nG19 G3 Y10 Z0 J5 K0 X3\nM2\n");
  auto m = moves(p);
  EXPECT_EQ(m[0], "ARC_FEED(0.0000, 10.0000, 0.0000, 5.0000, -1, 0.0000, 0.0000, 0.0000, 0.0000)");
  EXPECT_EQ(m[1], "ARC_FEED(10.0000, 0.0000, 5.0000, 0.0000, 1, 3.0000, 0.0000, 0.0000, 0.0000)");
  const ArcFeed* last = nullptr;
  for (const auto& c : p.calls)
    if (auto* a = std::get_if<ArcFeed>(&c.op)) last = a;
  ASSERT_TRUE(last);
  EXPECT_EQ(last->plane, Plane::kYZ) << "the canonical arc records its plane";
}

TEST(Arcs, AbsoluteCentresWithG90_1) {
  auto p = run("F100\nG0 X10 Y0\nG90.1 G3 X0 Y10 I0 J0\nM2\n");
  EXPECT_EQ(moves(p)[1],
            "ARC_FEED(0.0000, 10.0000, 0.0000, 0.0000, 1, 0.0000, 0.0000, 0.0000, 0.0000)");
}

TEST(Arcs, RadiusTolerance) {
  // 0.004 mm off: accepted.  0.5 mm off: rejected.
  EXPECT_NO_THROW(run("F100\nG2 X10.004 Y0 I5 J0\nM2\n"));
  auto e = error_of("F100\nG2 X10.5 Y0 I5 J0\nM2\n");
  EXPECT_EQ(e.where().line, 2);
  EXPECT_EQ(e.where().column, 13);  // the I word
  EXPECT_NE(e.message().find("radius mismatch"), std::string::npos);
  auto r = error_of("F100\nG2 X20 Y0 R5\nM2\n");
  EXPECT_EQ(r.where().column, 11);
  EXPECT_NE(r.message().find("too small"), std::string::npos);
}

TEST(InverseTime, FeedBecomesLengthTimesF) {
  auto p = run("G93 G1 X3 Y4 F2\nG1 A90 F0.5\nG2 X3 Y4 I1 F1\nM2\n");
  auto rates = calls_named(p, {"SET_FEED_RATE"});
  ASSERT_EQ(rates.size(), 4u);                    // the last one is M2's reset
  EXPECT_EQ(rates[0], "SET_FEED_RATE(10.0000)");  // 5 mm x 2/min
  EXPECT_EQ(rates[1], "SET_FEED_RATE(45.0000)");  // rotary only: 90 deg x 0.5
  EXPECT_EQ(rates[2], "SET_FEED_RATE(6.2832)");   // full circle r = 1
  for (const auto& c : p.calls)
    if (std::holds_alternative<ArcFeed>(c.op)) {
      EXPECT_EQ(c.context.feed_mode, FeedMode::kInverseTime);
      EXPECT_EQ(c.context.inverse_time_f, 1.0);
    }
}

TEST(Motion, MachinePositionFromContext) {
  auto p = run("G10 L2 P1 X100 Y0 Z0\nT1 M6 G43 H1\nG20 G0 X1 Y1 Z1\nM2\n");
  for (const auto& c : p.calls)
    if (auto* t = std::get_if<StraightTraverse>(&c.op)) {
      const Axes6 m = machine_position_mm(t->end, c.context);
      EXPECT_NEAR(m.x, 125.4, 1e-12);
      EXPECT_NEAR(m.y, 25.4, 1e-12);
      EXPECT_NEAR(m.z, 35.4, 1e-12);
    }
}

}  // namespace
}  // namespace truecut::interp::testing
