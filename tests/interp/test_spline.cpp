// BSPLINE / CSPLINE: the contour error against the programmed polyline, and
// node insertion that brings it inside the tolerance on a free-form path.
#include <numbers>

#include "planner_test_util.hpp"

namespace truecut::interp::testing {
namespace {

// A free-form test path: a curve of varying curvature, sampled as CAM would
// (chords of 1.5 to 4 mm) with a few sharp turns.
std::vector<Vec5> free_form() {
  std::vector<Vec5> p;
  double s = 0;
  for (int i = 0; i <= 40; ++i) {
    const double x = s, y = 8 * std::sin(s / 9) + 3 * std::sin(s / 2.3) + (i % 13 == 7 ? 2.5 : 0);
    p.push_back({x, y, -0.05 * s, 0, 0});
    s += 1.5 + 2.5 * (0.5 + 0.5 * std::sin(i * 1.7));
  }
  return p;
}

std::string spline_program(const char* word, const std::vector<Vec5>& pts) {
  std::ostringstream g;
  g << "G21 G90 G64\nG0 X" << pts[0][0] << " Y" << pts[0][1] << " Z" << pts[0][2] << "\nF1200\n"
    << word << "\n";
  for (size_t i = 1; i < pts.size(); ++i)
    g << "X" << pts[i][0] << " Y" << pts[i][1] << " Z" << pts[i][2] << "\n";
  g << "G1\nM2\n";
  return g.str();
}

TEST(Spline, BsplinePassesThroughTheEndsOnly) {
  const std::vector<Vec5> pts{{0, 0, 0, 0, 0}, {10, 0, 0, 0, 0}, {10, 10, 0, 0, 0}};
  const SplineFit f = fit_spline(SplineMode::kBspline, pts);
  ASSERT_EQ(2u, f.spans.size());
  EXPECT_EQ(pts[0], f.spans[0].c0);
  Vec5 end;
  for (int k = 0; k < 5; ++k)
    end[k] = f.spans[1].c0[k] + f.spans[1].c1[k] + f.spans[1].c2[k] + f.spans[1].c3[k];
  for (int k = 0; k < 5; ++k)
    EXPECT_NEAR(pts[2][k], end[k], 1e-12);
  // At the corner the curve cuts inside by d sin(beta) / 6 from the legs.
  EXPECT_NEAR(10.0 / 6.0, f.error_mm, 0.05);
}

TEST(Spline, CsplineInterpolatesThePoints) {
  const auto pts = free_form();
  const SplineFit f = fit_spline(SplineMode::kCspline, pts);
  ASSERT_EQ(pts.size() - 1, f.spans.size());
  for (size_t i = 0; i < f.spans.size(); ++i)
    for (int k = 0; k < 5; ++k)
      EXPECT_NEAR(pts[i][k], f.spans[i].c0[k], 1e-12);
}

TEST(Spline, NodeInsertionMeetsTheTolerance) {
  const auto pts = free_form();
  for (SplineMode mode : {SplineMode::kBspline, SplineMode::kCspline})
    for (double tol : {0.025, 0.01, 0.1}) {
      SplineReport r;
      const SplineFit f = fit_spline_within(mode, pts, tol, &r);
      EXPECT_GT(r.error_before_mm, tol) << "the test path must need insertion";
      EXPECT_LE(r.error_after_mm, tol);
      EXPECT_GT(r.nodes_inserted, 0);
      EXPECT_DOUBLE_EQ(r.error_after_mm, contour_error_mm(f.spans, pts));
      std::printf("%s tol %.3f: Er %.4f -> %.4f mm, %d nodes inserted\n",
                  mode == SplineMode::kBspline ? "BSPLINE" : "CSPLINE", tol, r.error_before_mm,
                  r.error_after_mm, r.nodes_inserted);
    }
}

TEST(Spline, PlannedMotionStaysWithinTheTolerance) {
  const auto pts = free_form();
  for (const char* word : {"BSPLINE", "CSPLINE"}) {
    PlannerOptions o;
    const Plan plan = plan_text(spline_program(word, pts), o);
    ASSERT_EQ(1u, plan.splines.size()) << word;
    EXPECT_TRUE(plan.splines[0].within_tolerance()) << word;
    const auto s = sample_plan(plan, o.servo_period_s);
    EXPECT_TRUE(check_limits(s, o.limits, o.servo_period_s).ok()) << word;
    double worst = 0;
    for (const auto& c : s) {
      const Vec5 q{c.tcp_mm[0], c.tcp_mm[1], c.tcp_mm[2], 0, 0};
      double best = 1e300;
      for (size_t i = 0; i + 1 < pts.size(); ++i) {
        SplineFit seg;
        best = std::min(best, contour_error_mm({CubicSpan{q, {}, {}, {}}}, {pts[i], pts[i + 1]}));
      }
      worst = std::max(worst, best);
    }
    EXPECT_LE(worst, o.spline_tolerance_mm + 1e-6) << word;
  }
}

TEST(Spline, WithoutInsertionTheErrorStays) {
  PlannerOptions o;
  o.spline_node_insertion = false;
  const Plan plan = plan_text(spline_program("BSPLINE", free_form()), o);
  ASSERT_EQ(1u, plan.splines.size());
  EXPECT_FALSE(plan.splines[0].within_tolerance());
}

TEST(Spline, SinumerikCorpusProgramPlans) {
  InterpreterOptions io;
  io.tools = ToolTable::parse("T1 P1 D6 Z10\n", "t");
  const CanonProgram p = Interpreter(io).run_file(truecut::test::source_dir() /
                                                  "tests/interp/corpus/sinumerik_5axis.ngc");
  PlannerOptions o;
  const Plan plan = plan_program(p, o);
  ASSERT_EQ(2u, plan.splines.size());
  for (const auto& r : plan.splines) {
    EXPECT_TRUE(r.within_tolerance());
    std::printf("corpus %s line %d: %d points, Er %.4f -> %.4f mm, %d nodes inserted\n",
                r.mode == SplineMode::kBspline ? "BSPLINE" : "CSPLINE", r.line, r.points,
                r.error_before_mm, r.error_after_mm, r.nodes_inserted);
  }
  const auto s = sample_plan(plan, o.servo_period_s);
  EXPECT_TRUE(check_limits(s, o.limits, o.servo_period_s).ok());
}

}  // namespace
}  // namespace truecut::interp::testing
