// Path control: blending inside the G64 P tolerance, exact path (G61),
// exact stop (G61.1), arcs and helices, dwell.
#include <iomanip>
#include <numbers>

#include "planner_test_util.hpp"

namespace truecut::interp::testing {
namespace {

using P3 = std::array<double, 3>;

double segment_distance(const P3& p, const P3& a, const P3& b) {
  P3 ab, ap;
  double dot = 0, l2 = 0;
  for (int i = 0; i < 3; ++i)
    ab[i] = b[i] - a[i], ap[i] = p[i] - a[i], dot += ab[i] * ap[i], l2 += ab[i] * ab[i];
  const double t = l2 > 0 ? std::clamp(dot / l2, 0.0, 1.0) : 0.0;
  double d = 0;
  for (int i = 0; i < 3; ++i)
    d += (a[i] + t * ab[i] - p[i]) * (a[i] + t * ab[i] - p[i]);
  return std::sqrt(d);
}

double polyline_distance(const P3& p, const std::vector<P3>& poly) {
  double best = 1e300;
  for (size_t i = 0; i + 1 < poly.size(); ++i)
    best = std::min(best, segment_distance(p, poly[i], poly[i + 1]));
  return best;
}

// A zig-zag with turns from 10 to 150 degrees.
std::vector<P3> zigzag() {
  std::vector<P3> p{{0, 0, 0}};
  double x = 0, y = 0, heading = 0;
  for (int i = 0; i < 12; ++i) {
    heading += (i % 2 ? -1 : 1) * (10 + 12.5 * i) * std::numbers::pi / 180;
    x += 5 * std::cos(heading), y += 5 * std::sin(heading);
    p.push_back({x, y, 0});
  }
  return p;
}

std::string program_for(const std::vector<P3>& pts, const std::string& mode) {
  std::ostringstream g;
  g << std::fixed << std::setprecision(9) << "G21 G90 " << mode << "\nG1 F3000\n";
  for (const auto& p : pts)
    g << "G1 X" << p[0] << " Y" << p[1] << " Z" << p[2] << "\n";
  g << "M2\n";
  return g.str();
}

struct PolylineRun {
  std::vector<CycleOutput> cycles;
  double max_deviation = 0;
  double duration_s = 0;
};

PolylineRun run_polyline(const std::string& mode) {
  const auto pts = zigzag();
  const Plan plan = plan_text(program_for(pts, mode));
  PolylineRun r;
  r.cycles = sample_plan(plan, 0.001);
  r.duration_s = plan.stats.duration_s;
  for (const auto& c : r.cycles)
    r.max_deviation = std::max(r.max_deviation, polyline_distance(c.tcp_mm, pts));
  return r;
}

TEST(PlannerPaths, BlendStaysWithinTolerance) {
  for (double tol : {0.001, 0.01, 0.1}) {
    const PolylineRun r = run_polyline("G64 P" + std::to_string(tol));
    EXPECT_LE(r.max_deviation, tol + 1e-9) << tol;
    EXPECT_GT(r.max_deviation, 0.5 * tol) << "the corners were not blended at P" << tol;
  }
}

TEST(PlannerPaths, LargerToleranceIsFaster) {
  // A CAM-like polyline: 2 mm chords turning by 3 to 8 degrees.
  std::vector<P3> pts{{0, 0, 0}};
  double heading = 0;
  for (int i = 0; i < 40; ++i) {
    heading += (i % 2 ? -1 : 1) * (3 + (i % 6)) * std::numbers::pi / 180;
    pts.push_back(
        {pts.back()[0] + 2 * std::cos(heading), pts.back()[1] + 2 * std::sin(heading), 0});
  }
  auto duration = [&](const std::string& mode) {
    return plan_text(program_for(pts, mode)).stats.duration_s;
  };
  const double tight = duration("G64 P0.0005"), loose = duration("G64 P0.05"),
               unbounded = duration("G64"), stop = duration("G61");
  EXPECT_LT(loose, tight);
  EXPECT_LE(unbounded, loose);
  EXPECT_LT(tight, stop);
}

// The plan comes to rest where each programmed move ends, and the sampled
// path never leaves the polyline.
void expect_stops_at_corners(const std::string& mode) {
  const auto pts = zigzag();
  const Plan plan = plan_text(program_for(pts, mode));
  int rests = 0;
  for (const PlanSegment& s : plan.segments) {
    const LawState end = evaluate(s.law, s.law.duration_s);
    if (std::abs(end.v) < 1e-9 && std::abs(end.a) < 1e-9) ++rests;
  }
  EXPECT_GE(rests, static_cast<int>(pts.size()) - 1) << mode;
  EXPECT_EQ(static_cast<int>(pts.size()) - 2, plan.stats.exact_stops) << mode;
  double worst = 0;
  for (const auto& c : sample_plan(plan, 0.001))
    worst = std::max(worst, polyline_distance(c.tcp_mm, pts));
  EXPECT_LT(worst, 1e-9) << mode;
}

TEST(PlannerPaths, ExactStopStopsAtEveryCorner) {
  expect_stops_at_corners("G61.1");
}

TEST(PlannerPaths, ExactPathStopsAtCorners) {
  expect_stops_at_corners("G61");
}

TEST(PlannerPaths, ExactStopStopsBetweenCollinearMoves) {
  const Plan stop = plan_text("G61.1 G1 X10 F3000\nX20\nM2\n");
  const Plan path = plan_text("G61 G1 X10 F3000\nX20\nM2\n");
  EXPECT_EQ(1, stop.stats.exact_stops);
  EXPECT_EQ(0, path.stats.exact_stops);  // G61 does not stop between collinear moves
}

TEST(PlannerPaths, HelixStaysOnItsCylinder) {
  const auto s =
      sample_plan(plan_text("G17 G1 X10 Y0 Z0 F1200\nG3 X10 Y0 Z-6 I-10 J0 P3\nM2\n"), 0.001);
  double worst = 0, z_prev = 1;
  for (const auto& c : s) {
    if (c.line != 2) continue;
    worst = std::max(worst, std::abs(std::hypot(c.tcp_mm[0], c.tcp_mm[1]) - 10));
    EXPECT_LE(c.tcp_mm[2], z_prev + 1e-12);  // descends monotonically
    z_prev = c.tcp_mm[2];
  }
  EXPECT_LT(worst, 1e-9);
  EXPECT_NEAR(-6, s.back().tcp_mm[2], 1e-9);
  // Three turns at 20 mm/s of helix length take at least that long.
  const double helix = std::hypot(3 * 2 * std::numbers::pi * 10, 6);
  EXPECT_GE(s.size() * 0.001, helix / 20);
}

TEST(PlannerPaths, ArcsInAllPlanesEndWhereProgrammed) {
  for (const char* prog :
       {"G18 G1 X10 F600\nG2 X0 Z10 I-10 K0\nM2\n", "G19 G1 Y10 F600\nG3 Y0 Z10 J-10 K0\nM2\n",
        "G17 G1 X10 F600\nG2 X-10 Y0 R10\nM2\n"}) {
    const CanonProgram program = run(prog);
    const auto s = sample_plan(plan_program(program, {}), 0.001);
    const auto arc =
        std::find_if(program.calls.begin(), program.calls.end(),
                     [](const CanonCall& c) { return std::holds_alternative<ArcFeed>(c.op); });
    ASSERT_NE(arc, program.calls.end());
    const Axes6 end = std::get<ArcFeed>(arc->op).end;
    EXPECT_NEAR(end.x, s.back().joints[0], 1e-9) << prog;
    EXPECT_NEAR(end.y, s.back().joints[1], 1e-9) << prog;
    EXPECT_NEAR(end.z, s.back().joints[2], 1e-9) << prog;
    EXPECT_TRUE(check_limits(s, PlannerOptions{}.limits, 0.001).ok()) << prog;
  }
}

TEST(PlannerPaths, DwellHoldsStill) {
  const auto s = sample_plan(plan_text("G1 X10 F1200\nG4 P0.25\nG1 X20\nM2\n"), 0.001);
  int still = 0, longest = 0;
  for (size_t n = 1; n < s.size(); ++n) {
    still = s[n].joints[0] == 10.0 && s[n - 1].joints[0] == 10.0 ? still + 1 : 0;
    longest = std::max(longest, still);
  }
  EXPECT_GE(longest, 249);
  EXPECT_LE(longest, 252);
}

// Canned cycles expand into traverses, feeds, dwells and spindle calls: the
// planner runs them like any other moves, to every hole bottom and back.
TEST(PlannerPaths, CannedCyclesReachEveryHoleBottom) {
  const CanonProgram program =
      run("G21 G90 G98\nS1000 M3\nG0 X0 Y0 Z10\nG83 X10 Y5 Z-3 R2 Q1.2 F600\n"
          "G81 X20 Z-2 R2\nG91 G82 X5 Z-4 R-8 P0.2 L2\nG90 G86 X40 Z-1 R1 P0.1\nG80\nM2\n");
  const auto s = sample_plan(plan_program(program, {}), 0.001);
  ASSERT_FALSE(s.empty());
  EXPECT_TRUE(s.back().done);
  EXPECT_TRUE(check_limits(s, PlannerOptions{}.limits, 0.001).ok());
  const P3 bottoms[] = {{10, 5, -3}, {20, 5, -2}, {25, 5, -2}, {30, 5, -2}, {40, 5, -1}};
  for (const P3& b : bottoms) {
    double closest = 1e300;
    for (const auto& c : s)
      closest =
          std::min(closest, std::hypot(c.tcp_mm[0] - b[0], c.tcp_mm[1] - b[1], c.tcp_mm[2] - b[2]));
    EXPECT_LT(closest, 1e-6) << "hole bottom " << b[0] << " " << b[1] << " " << b[2];
  }
  // G98: back to the initial level Z10 after the last hole.
  EXPECT_NEAR(s.back().tcp_mm[0], 40, 1e-9);
  EXPECT_NEAR(s.back().tcp_mm[2], 10, 1e-9);
}

// Cutter radius compensation (G41): the planner runs the compensated path,
// the 20 mm square profiled from inside by tool T1 (D6, radius 3): round
// the convex corner after the entry at 3 mm from it, then along the square
// 3 mm in from the sides.
TEST(PlannerPaths, CutterCompensationRunsTheOffsetPath) {
  const auto s =
      sample_plan(plan_text("G21 G61 T1 M6\nG0 X-10 Y-10\nG41 D1 G1 X0 Y0 F1200\nX20\nY20\nX0\nY0\n"
                            "G40 G1 X-10 Y-10\nM2\n"),
                  0.001);
  ASSERT_FALSE(s.empty());
  EXPECT_TRUE(s.back().done);
  const P3 corners[] = {{17, 3, 0}, {17, 17, 0}, {3, 17, 0}, {3, 0, 0}};
  for (const P3& k : corners) {
    double closest = 1e300;
    for (const auto& c : s)
      closest = std::min(closest, std::hypot(c.tcp_mm[0] - k[0], c.tcp_mm[1] - k[1]));
    EXPECT_LT(closest, 1e-6) << "corner " << k[0] << " " << k[1];
  }
  for (const auto& c : s) {
    if (c.line == 4) {
      EXPECT_GE(std::hypot(c.tcp_mm[0], c.tcp_mm[1]), 3 - 1e-6);
    }
    if (c.line != 5 && c.line != 6) continue;  // sides Y20 and X0
    EXPECT_GE(c.tcp_mm[0], 3 - 1e-9);
    EXPECT_LE(c.tcp_mm[0], 17 + 1e-9);
    EXPECT_GE(c.tcp_mm[1], 3 - 1e-9);
    EXPECT_LE(c.tcp_mm[1], 17 + 1e-9);
  }
}

// G10 L2 R: the machine runs the program turned about Z. A G18 arc stands
// in the turned vertical plane, a G17 circle keeps its radius about the
// turned centre (machine XY = G5x + rotation x program).
TEST(PlannerPaths, RotatedCoordinateSystemTurnsLinesAndArcs) {
  const auto s = sample_plan(plan_text("G21 G61\nG10 L2 P1 X10 Y5 R30\nG0 X0 Y0 Z0\n"
                                       "G18 G2 X10 Z0 I5 K0 F600\nG17 G2 X10 Y0 I-5 J0\n"
                                       "G1 X0 Y0\nM2\n"),
                             0.001);
  ASSERT_FALSE(s.empty());
  EXPECT_TRUE(s.back().done);
  const double c30 = std::cos(std::numbers::pi / 6), s30 = std::sin(std::numbers::pi / 6);
  auto machine = [&](double x, double y) {
    return P3{10 + c30 * x - s30 * y, 5 + s30 * x + c30 * y, 0};
  };
  const P3 centre = machine(5, 0);
  double z0 = 0, top = 0;
  int on_arc = 0, on_circle = 0;
  for (const auto& c : s) {
    if (c.line == 3) z0 = c.tcp_mm[2];
    if (c.line == 4) {
      ++on_arc;
      const double dx = c.tcp_mm[0] - centre[0], dy = c.tcp_mm[1] - centre[1];
      const double dz = c.tcp_mm[2] - z0;
      EXPECT_NEAR(std::sqrt(dx * dx + dy * dy + dz * dz), 5, 1e-6);
      EXPECT_NEAR(-s30 * dx + c30 * dy, 0, 1e-6);  // in the turned XZ plane
      top = std::max(top, std::abs(dz));
    }
    if (c.line == 5) {
      ++on_circle;
      EXPECT_NEAR(std::hypot(c.tcp_mm[0] - centre[0], c.tcp_mm[1] - centre[1]), 5, 1e-6);
      EXPECT_NEAR(c.tcp_mm[2], z0, 1e-9);
    }
  }
  EXPECT_GT(on_arc, 10);
  EXPECT_GT(on_circle, 10);
  EXPECT_NEAR(top, 5, 1e-3);
  const P3 end = machine(0, 0);
  EXPECT_NEAR(s.back().tcp_mm[0], end[0], 1e-9);
  EXPECT_NEAR(s.back().tcp_mm[1], end[1], 1e-9);
}

}  // namespace
}  // namespace truecut::interp::testing
