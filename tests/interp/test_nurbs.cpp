// G5, G5.1, G5.2/G5.3: the curve of a NURBS_FEED call (nurbs.hpp) against
// closed forms, the control points the interpreter gives it, and the
// planner's chords within its tolerance (docs/gcode.md "Splines G5.x").
#include <cmath>
#include <numbers>

#include "planner_test_util.hpp"
#include "truecut/interp/nurbs.hpp"

namespace truecut::interp::testing {
namespace {

NurbsFeed curve(std::vector<NurbsControlPoint> points, int order) {
  NurbsFeed n;
  n.points = std::move(points);
  n.order = order;
  return n;
}

// The calls' NURBS, in program order.
std::vector<NurbsFeed> nurbs_of(const CanonProgram& p) {
  std::vector<NurbsFeed> out;
  for (const auto& c : p.calls)
    if (const auto* n = std::get_if<NurbsFeed>(&c.op)) out.push_back(*n);
  return out;
}

TEST(Nurbs, CubicIsTheBezierCurveOfItsFourPoints) {
  const NurbsFeed n = curve({{0, 0, 1}, {1, 3, 1}, {4, 3, 1}, {5, 0, 1}}, 4);
  EXPECT_EQ(nurbs_parameter_end(n), 1);
  for (double u = 0; u <= 1; u += 0.05) {
    const double a = (1 - u) * (1 - u) * (1 - u), b = 3 * u * (1 - u) * (1 - u),
                 c = 3 * u * u * (1 - u), d = u * u * u;
    const NurbsPoint2 p = nurbs_point(n, u);
    EXPECT_NEAR(p[0], b * 1 + c * 4 + d * 5, 1e-12) << u;
    EXPECT_NEAR(p[1], b * 3 + c * 3, 1e-12) << u;
    (void)a;
  }
}

TEST(Nurbs, QuadraticWithTheRightWeightIsACircle) {
  // (1,0) (1,1) (0,1) with the middle weight cos 45 deg: a quarter circle.
  const NurbsFeed n = curve({{1, 0, 1}, {1, 1, std::sqrt(0.5)}, {0, 1, 1}}, 3);
  double worst = 0;
  for (double u = 0; u <= 1; u += 0.01) {
    const NurbsPoint2 p = nurbs_point(n, u);
    worst = std::max(worst, std::abs(std::hypot(p[0], p[1]) - 1));
  }
  EXPECT_LT(worst, 1e-12);
  // With weight 1 it is the parabola, which lies outside the circle.
  const NurbsFeed parabola = curve({{1, 0, 1}, {1, 1, 1}, {0, 1, 1}}, 3);
  const NurbsPoint2 m = nurbs_point(parabola, 0.5);
  EXPECT_NEAR(m[0], 0.75, 1e-12);
  EXPECT_GT(std::hypot(m[0], m[1]), 1.01);
}

TEST(Nurbs, LongerCurvesAreClampedAndPiecewise) {
  // Six points of order 4: three knot spans (0, 1, 2, 3), the ends at the
  // first and last points, equal weights scale away.
  std::vector<NurbsControlPoint> pts = {{0, 0, 1}, {1, 2, 1}, {3, 2, 1},
                                        {4, 0, 1}, {6, 1, 1}, {7, 3, 1}};
  const NurbsFeed a = curve(pts, 4);
  for (auto& p : pts)
    p.weight = 2.5;
  const NurbsFeed b = curve(pts, 4);
  EXPECT_EQ(nurbs_parameter_end(a), 3);
  EXPECT_EQ(nurbs_point(a, 0), (NurbsPoint2{0, 0}));
  EXPECT_EQ(nurbs_point(a, 3), (NurbsPoint2{7, 3}));
  for (double u = 0; u <= 3; u += 0.1) {
    EXPECT_NEAR(nurbs_point(a, u)[0], nurbs_point(b, u)[0], 1e-12);
    EXPECT_NEAR(nurbs_point(a, u)[1], nurbs_point(b, u)[1], 1e-12);
  }
  // A heavier weight pulls the curve toward its point.
  pts[2].weight = 10;
  const NurbsFeed c = curve(pts, 4);
  const auto d = [](NurbsPoint2 p) { return std::hypot(p[0] - 3, p[1] - 2); };
  EXPECT_LT(d(nurbs_point(c, 1.5)), d(nurbs_point(b, 1.5)));
}

// Largest distance from the curve (densely sampled) to a polyline.
double distance_to_polyline(const NurbsFeed& n, const std::vector<NurbsPoint2>& line) {
  double worst = 0;
  const double end = nurbs_parameter_end(n);
  for (int i = 0; i <= 20000; ++i) {
    const NurbsPoint2 p = nurbs_point(n, end * i / 20000);
    double best = 1e300;
    for (size_t k = 0; k + 1 < line.size(); ++k) {
      const double dx = line[k + 1][0] - line[k][0], dy = line[k + 1][1] - line[k][1];
      const double l2 = dx * dx + dy * dy;
      double t = l2 > 0 ? ((p[0] - line[k][0]) * dx + (p[1] - line[k][1]) * dy) / l2 : 0;
      t = std::clamp(t, 0.0, 1.0);
      best = std::min(best, std::hypot(p[0] - line[k][0] - t * dx, p[1] - line[k][1] - t * dy));
    }
    worst = std::max(worst, best);
  }
  return worst;
}

TEST(Nurbs, PolylineStaysWithinItsTolerance) {
  const NurbsFeed n =
      curve({{0, 0, 1}, {10, 30, 2}, {20, -30, 0.5}, {30, 30, 1}, {40, 0, 3}, {45, 5, 1}}, 4);
  for (double tol : {0.1, 0.025, 0.001}) {
    const auto chords = nurbs_polyline(n, tol);
    std::vector<NurbsPoint2> line = {{0, 0}};
    line.insert(line.end(), chords.begin(), chords.end());
    EXPECT_EQ(line.back(), (NurbsPoint2{45, 5}));
    const double worst = distance_to_polyline(n, line);
    EXPECT_LE(worst, tol) << tol;
    std::printf("tolerance %.3f: %zu chords, largest distance %.5f\n", tol, chords.size(), worst);
  }
}

TEST(Nurbs, InterpreterControlPoints) {
  // G5: start, start + (I, J), end + (P, Q), end; the next G5 without I J
  // starts along the last one's end direction (-P, -Q). G5.1: start,
  // start + (I, J), end.
  const CanonProgram p =
      run("G21 G0 X1 Y2 Z3\nF100\nG5 I1 J2 P3 Q4 X10 Y5\nG5 P-1 Q0 X20 Y0\nG5.1 I1 J-1 X25 Y1\n"
          "G91 G5.1 I1 J1 X2 Y2\nM2\n");
  const auto n = nurbs_of(p);
  ASSERT_EQ(n.size(), 4u);
  auto xy = [](const NurbsFeed& f) {
    std::vector<double> out;
    for (const auto& c : f.points) {
      out.push_back(c.x);
      out.push_back(c.y);
    }
    return out;
  };
  EXPECT_EQ(n[0].order, 4);
  EXPECT_EQ(xy(n[0]), (std::vector<double>{1, 2, 2, 4, 13, 9, 10, 5}));
  EXPECT_EQ(xy(n[1]), (std::vector<double>{10, 5, 7, 1, 19, 0, 20, 0}));
  EXPECT_EQ(n[2].order, 3);
  EXPECT_EQ(xy(n[2]), (std::vector<double>{20, 0, 21, -1, 25, 1}));
  EXPECT_EQ(xy(n[3]), (std::vector<double>{25, 1, 26, 2, 27, 3}));
  EXPECT_EQ(n[3].end, (Axes6{27, 3, 3, 0, 0, 0}));
}

TEST(Nurbs, InterpreterNurbsRun) {
  // G5.2 ... G5.3: the start with weight P of a first block without X Y,
  // then each point with its weight; L sets the order; G91 points count
  // from the start (rs274).
  const CanonProgram p =
      run("G21 G0 X1 Y1\nF100\nG5.2 P2 L4\nX2 Y3 P1\nX4 Y3 P3\nX5 Y1 P1\nG5.3\n"
          "G91 G5.2 X1 Y1 P1\nX2 Y0 P1\nG5.3\nM2\n");
  const auto n = nurbs_of(p);
  ASSERT_EQ(n.size(), 2u);
  EXPECT_EQ(n[0].order, 4);
  ASSERT_EQ(n[0].points.size(), 4u);
  EXPECT_EQ(n[0].points[0].weight, 2);
  EXPECT_EQ(n[0].points[2].weight, 3);
  EXPECT_EQ(n[0].end.x, 5);
  EXPECT_EQ(n[1].order, 3);
  ASSERT_EQ(n[1].points.size(), 3u);
  EXPECT_EQ(n[1].points[1].x, 6);
  EXPECT_EQ(n[1].points[2].x, 7);
  EXPECT_EQ(n[1].end, (Axes6{7, 1, 0, 0, 0, 0}));
}

TEST(Nurbs, TruecutRefusesWhatRs274WouldRunWrongly) {
  // An open G5.2 run before another motion code or the end (rs274 drops
  // it), a first point without weight (rs274 takes -1), Z in G5.2 (rs274
  // ignores it), G5.2 under cutter compensation.
  const std::pair<const char*, const char*> cases[] = {
      {"G21 F100\nG5.2 X1 Y1 P1\nX2 Y2 P1\nG1 X3\nM2\n",
       "test.ngc:4:1: the G5.2 NURBS started at line 2"},
      {"G21 F100\nG5.2 X1 Y1 P1\nX2 Y2 P1\nM2\n", "test.ngc:4:"},
      {"G21 F100\nG5.2 X1 Y1\nX2 Y2 P1\nG5.3\nM2\n", "test.ngc:2:"},
      {"G21 F100\nG5.2 X1 Y1 P1\nX2 Y2 Z1 P1\nG5.3\nM2\n", "test.ngc:3:7:"},
      {"G21 F100\nG41.1 D1 G1 X1\nG5.2 X1 Y1 P1\nX2 Y2 P1\nG5.3\nM2\n", "test.ngc:3:"},
  };
  for (const auto& [text, where] : cases) {
    try {
      run(text);
      ADD_FAILURE() << text << "ran";
    } catch (const GcodeError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(where, 0), 0u) << e.what();
    }
  }
}

// The planner runs a NURBS as chords within spline_tolerance_mm: every
// cycle of the planned motion lies within it of the curve, in G61 and in
// G64 P0.01 (G64 without P may cut the corners between the curves), within
// the machine limits, and the move ends at the curve's end.
TEST(Nurbs, PlannedMotionFollowsTheCurve) {
  const std::string body =
      "G0 X0 Y0 Z0\nF2000\nG5 I10 J30 P-10 Q30 X40 Y0\nG5.2 X50 Y20 P1 L4\nX60 Y-20 P2\n"
      "X70 Y10 P0.5\nX80 Y0 P1\nG5.3\nG5.1 I5 J-20 X100 Y0\nG1 Z1\nM2\n";
  for (const char* mode : {"G61", "G64 P0.01"}) {
    const std::string text = std::string("G21 G90 ") + mode + "\n" + body;
    const CanonProgram program = run(text);
    const auto curves = nurbs_of(program);
    ASSERT_EQ(curves.size(), 3u);
    PlannerOptions o;
    const Plan plan = plan_program(program, o);
    const auto s = sample_plan(plan, o.servo_period_s);
    EXPECT_TRUE(check_limits(s, o.limits, o.servo_period_s).ok()) << mode;
    // The feed samples at Z 0 (before the last move) against the curves'
    // dense polylines.
    std::vector<NurbsPoint2> dense;
    for (const auto& c : curves) {
      const double end = nurbs_parameter_end(c);
      for (int i = 0; i <= 4000; ++i)
        dense.push_back(nurbs_point(c, end * i / 4000));
    }
    double worst = 0;
    int checked = 0;
    for (const auto& c : s) {
      if (std::abs(c.tcp_mm[2]) > 1e-9 || c.tcp_mm[0] < 1e-9) continue;
      double best = 1e300;
      for (size_t k = 0; k + 1 < dense.size(); ++k) {
        const double dx = dense[k + 1][0] - dense[k][0], dy = dense[k + 1][1] - dense[k][1];
        const double l2 = dx * dx + dy * dy;
        double t =
            l2 > 0 ? ((c.tcp_mm[0] - dense[k][0]) * dx + (c.tcp_mm[1] - dense[k][1]) * dy) / l2 : 0;
        t = std::clamp(t, 0.0, 1.0);
        best = std::min(best, std::hypot(c.tcp_mm[0] - dense[k][0] - t * dx,
                                         c.tcp_mm[1] - dense[k][1] - t * dy));
      }
      worst = std::max(worst, best);
      ++checked;
    }
    EXPECT_GT(checked, 100) << mode;
    EXPECT_LE(worst, o.spline_tolerance_mm) << mode;
    std::printf("%s: %d cycles on the curves, largest distance %.5f mm\n", mode, checked, worst);
    EXPECT_NEAR(s.back().tcp_mm[0], 100, 1e-9);
    EXPECT_NEAR(s.back().tcp_mm[1], 0, 1e-9);
    EXPECT_NEAR(s.back().tcp_mm[2], 1, 1e-9);
  }
}

TEST(Nurbs, PlannerRefusesANurbsInInverseTimeWithoutF) {
  const CanonProgram p = run("G21 G0 X0 Y0\nG93\nG5.2 X1 Y1 P1\nX2 Y0 P1\nG5.3\nG94\nM2\n");
  try {
    plan_program(p, PlannerOptions{});
    ADD_FAILURE() << "planned";
  } catch (const GcodeError& e) {
    EXPECT_NE(std::string(e.what()).find("G93"), std::string::npos) << e.what();
  }
  // With F on the G5.3 line the NURBS takes 1/F minutes.
  const CanonProgram q = run("G21 G0 X0 Y0\nG93\nG5.2 X10 Y10 P1\nX20 Y0 P1\nG5.3 F6\nG94\nM2\n");
  PlannerOptions o;
  o.limits.axis[0] = {1e4, 1e6, 1e9};
  o.limits.axis[1] = {1e4, 1e6, 1e9};
  const Plan plan = plan_program(q, o);
  EXPECT_NEAR(plan.stats.duration_s, 10.0, 0.5);
}

}  // namespace
}  // namespace truecut::interp::testing
