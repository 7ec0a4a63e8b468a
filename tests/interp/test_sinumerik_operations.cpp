// Sinumerik words (TRAORI/TRAFOOF, BSPLINE/CSPLINE and back to G1) and CAM
// operation names taken from comments.
#include <gtest/gtest.h>

#include "interp_test_util.hpp"
#include "test_paths.hpp"
#include "truecut/interp/operations.hpp"

namespace truecut::interp::testing {
namespace {

TEST(Sinumerik, TraoriIsRecordedOnEveryMove) {
  auto p = run("G1 X1 F100\nTRAORI\nG1 X2 A10 C20\ntraori(1) G1 X3\nTRAFOOF\nG1 X4\nM2\n");
  std::vector<bool> tcp;
  for (const auto& c : p.calls)
    if (std::holds_alternative<StraightFeed>(c.op)) tcp.push_back(c.context.tcp);
  EXPECT_EQ(tcp, (std::vector<bool>{false, true, true, false}));
  EXPECT_EQ(calls_named(p, {"SET_TCP"}),
            (std::vector<std::string>{"SET_TCP(ON)", "SET_TCP(ON)", "SET_TCP(OFF)"}));
}

TEST(Sinumerik, SplineModesAreInTheMotionGroup) {
  auto p =
      run("G1 X0 F100\nBSPLINE\nX1 Y1\nX2 Y0\nCSPLINE X3 Y1\nX4\nG1 X5\nBSPLINE X6\nG0 X7\nM2\n");
  std::vector<SplineMode> modes;
  for (const auto& c : p.calls)
    if (is_motion(c.op)) modes.push_back(c.context.spline);
  using S = SplineMode;
  EXPECT_EQ(modes, (std::vector<S>{S::kNone, S::kBspline, S::kBspline, S::kCspline, S::kCspline,
                                   S::kNone, S::kBspline, S::kNone}));
  EXPECT_EQ(calls_named(p, {"SET_SPLINE_MODE"}),
            (std::vector<std::string>{"SET_SPLINE_MODE(BSPLINE)", "SET_SPLINE_MODE(CSPLINE)",
                                      "SET_SPLINE_MODE(NONE)", "SET_SPLINE_MODE(BSPLINE)",
                                      "SET_SPLINE_MODE(NONE)"}));
  // Spline points are feed moves: they need a feed rate.
  EXPECT_NE(error_of("BSPLINE X1\nM2\n").message().find("zero feed rate"), std::string::npos);
}

TEST(Sinumerik, SplineAndGCodeMotionConflict) {
  auto e = error_of("G1 BSPLINE X1 F100\nM2\n");
  EXPECT_EQ(e.where().column, 4);
  EXPECT_NE(e.message().find("motion modes"), std::string::npos);
}

TEST(Sinumerik, KeywordsInsideCommentsAreText) {
  auto p = run("G0 X1 (TRAORI here is a comment)\nM2\n");
  EXPECT_TRUE(calls_named(p, {"SET_TCP"}).empty());
}

TEST(Operations, CommentRule) {
  EXPECT_EQ(operation_from_comment("OPERATION: ROUGH"), "ROUGH");
  EXPECT_EQ(operation_from_comment(" Operation 3: Face mill 1 "), "Face mill 1");
  EXPECT_EQ(operation_from_comment("op=DRILL"), "DRILL");
  EXPECT_EQ(operation_from_comment("TOOLPATH: finish"), "finish");
  EXPECT_EQ(operation_from_comment("JOB 2 : pocket"), "pocket");
  EXPECT_EQ(operation_from_comment("OPTIONAL STOP"), std::nullopt);
  EXPECT_EQ(operation_from_comment("OPERATION"), std::nullopt);
  EXPECT_EQ(operation_from_comment("operation:"), std::nullopt);
  EXPECT_EQ(operation_from_comment("change tool"), std::nullopt);
}

TEST(Operations, MovesOfANamedOperation) {
  auto p =
      run("G0 X0\n(OPERATION: ROUGH)\nG1 X1 F100\nG1 X2\n;OPERATION: FINISH\nG2 X4 I1\n"
          "(OPERATION: ROUGH)\nG0 Z5\nM30\nG0 X9\n");
  EXPECT_EQ(operation_names(p), (std::vector<std::string>{"ROUGH", "FINISH"}));
  EXPECT_EQ(moves_of_operation(p, "ROUGH").size(), 3u);
  auto finish = moves_of_operation(p, "FINISH");
  ASSERT_EQ(finish.size(), 1u);
  EXPECT_TRUE(std::holds_alternative<ArcFeed>(finish[0].op));
  EXPECT_EQ(finish[0].context.line, 6);
  EXPECT_TRUE(moves_of_operation(p, "NONE").empty());
  EXPECT_TRUE(p.calls.back().context.operation.empty()) << "the program end closes the operation";
}

TEST(Operations, CorpusProgramWithTcpSplinesAndOperations) {
  InterpreterOptions o;
  o.tools = sample_tools();
  auto p = Interpreter(o).run_file(truecut::test::source_dir() /
                                   "tests/interp/corpus/sinumerik_5axis.ngc");
  EXPECT_EQ(operation_names(p), (std::vector<std::string>{"FACE_MILL", "CONTOUR 2"}));
  int tcp = 0, bspline = 0, cspline = 0;
  for (const auto& c : moves_of_operation(p, "FACE_MILL")) {
    tcp += c.context.tcp;
    bspline += c.context.spline == SplineMode::kBspline;
    cspline += c.context.spline == SplineMode::kCspline;
    EXPECT_EQ(c.context.tool, 1);
  }
  EXPECT_EQ(tcp, 7);
  EXPECT_EQ(bspline, 3);
  EXPECT_EQ(cspline, 2);
  EXPECT_EQ(moves_of_operation(p, "CONTOUR 2").size(), 1u);
}

}  // namespace
}  // namespace truecut::interp::testing
