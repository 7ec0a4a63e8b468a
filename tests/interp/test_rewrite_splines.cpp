// truecut::interp::rewrite_program on LinuxCNC's splines (issue 22, point
// 5): a G5, G5.1 or NURBS block of the rewritten operation is written as G1
// chords of its curve, each point corrected; splines outside the operation
// are copied; a NURBS block that would start from a corrected point is
// refused by name; a G5/G5.1 of another operation right after a corrected
// point gets a G1 back to the original point before it. The curves here are the test's own Bezier
// formulas from the words of the program (G5: P1 = start + (I, J), P2 = end + (P, Q); G5.1: P1 =
// start + (I, J)), not the interpreter's NURBS code.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "rewrite_test_util.hpp"
#include "truecut/interp/error.hpp"
#include "truecut/interp/rewrite.hpp"

namespace truecut::interp {
namespace {

using V = Eigen::Vector3d;
using P2 = std::array<double, 2>;

const V kShift(0.02, -0.01, 0.005);

CompensationMatrixData constant_matrix() {
  return testing::plane_matrix(-10, 10, -10, 10, 0, 0.5, kShift);
}

RewriteOptions options() {
  RewriteOptions o;
  o.operation = "FACE";
  o.type = CutType::kFace;
  o.interpreter.tools = ToolTable::parse("T2 P2 D4 Z40\n", "tools.tbl");
  o.reach_mm = 100;
  o.decimals = 7;
  return o;
}

// Distance from p to the curve c(t), t in [0, 1]: the nearest of 2000
// samples, refined by a ternary search between its neighbours.
double distance_to_curve(const P2& p, const std::function<P2(double)>& c) {
  auto dist = [&](double t) {
    const P2 q = c(t);
    return std::hypot(p[0] - q[0], p[1] - q[1]);
  };
  constexpr int kSamples = 2000;
  int best = 0;
  for (int k = 1; k <= kSamples; ++k)
    if (dist(static_cast<double>(k) / kSamples) < dist(static_cast<double>(best) / kSamples))
      best = k;
  double lo = std::max(0, best - 1) / static_cast<double>(kSamples);
  double hi = std::min(kSamples, best + 1) / static_cast<double>(kSamples);
  for (int i = 0; i < 100; ++i) {
    const double a = lo + (hi - lo) / 3, b = hi - (hi - lo) / 3;
    if (dist(a) < dist(b))
      hi = b;
    else
      lo = a;
  }
  return dist((lo + hi) / 2);
}

// The G1 feeds of the rewritten program at z = 0 (the cut), shifted back.
std::vector<P2> cut_points(const std::string& text) {
  const CanonProgram p = Interpreter(options().interpreter).run_text(text, "s.ngc");
  std::vector<P2> out;
  for (const CanonCall& c : p.calls) {
    EXPECT_FALSE(std::holds_alternative<NurbsFeed>(c.op)) << text;
    if (const auto* f = std::get_if<StraightFeed>(&c.op))
      if (std::fabs(f->end.z - kShift.z()) < 1e-9)
        out.push_back({f->end.x - kShift.x(), f->end.y - kShift.y()});
  }
  return out;
}

void expect_on_curve(const std::string& program, const std::function<P2(double)>& curve,
                     const P2& end,
                     const std::string& note =
                         "(truecut rewrite: 1 G5/G5.1 splines of operation "
                         "FACE written as G1 chords within 0.001 mm of the "
                         "curve, corrected)") {
  const RewriteOptions o = options();
  const RewriteResult r = rewrite_program(program, "s.ngc", constant_matrix(), o);
  EXPECT_NE(r.text.find(note), std::string::npos) << r.text;
  const std::vector<P2> pts = cut_points(r.text);
  ASSERT_GE(pts.size(), 8u) << r.text;
  for (const P2& p : pts)
    EXPECT_LT(distance_to_curve(p, curve), 1e-6) << p[0] << " " << p[1] << "\n" << r.text;
  EXPECT_NEAR(pts.back()[0], end[0], 1e-7);
  EXPECT_NEAR(pts.back()[1], end[1], 1e-7);
  // Chords within the tolerance: the curve between two written points never
  // leaves their chord by more than 1 um (checked at the curve's samples
  // that fall between them).
  double worst = 0;
  for (int k = 0; k <= 4000; ++k) {
    const P2 q = curve(k / 4000.0);
    double d = 1e300;
    for (size_t i = 0; i + 1 < pts.size(); ++i) {
      const double ax = pts[i][0], ay = pts[i][1], bx = pts[i + 1][0], by = pts[i + 1][1];
      const double len2 = (bx - ax) * (bx - ax) + (by - ay) * (by - ay);
      const double t =
          std::clamp(((q[0] - ax) * (bx - ax) + (q[1] - ay) * (by - ay)) / len2, 0.0, 1.0);
      d = std::min(d, std::hypot(ax + t * (bx - ax) - q[0], ay + t * (by - ay) - q[1]));
    }
    worst = std::max(worst, d);
  }
  EXPECT_LT(worst, o.chord_tolerance_mm + 1e-6);
}

// The quadratic Bezier curve through p0 and p2 with control point p1.
std::function<P2(double)> quadratic_bezier(const P2& p0, const P2& p1, const P2& p2) {
  return [=](double t) {
    const double a = (1 - t) * (1 - t), b = 2 * t * (1 - t), c = t * t;
    return P2{a * p0[0] + b * p1[0] + c * p2[0], a * p0[1] + b * p1[1] + c * p2[1]};
  };
}

TEST(RewriteSplines, AQuadraticSplineIsWrittenAsCorrectedChordsOfItsCurve) {
  const std::string program =
      "G21 G90 G94\n(OPERATION: FACE)\nT2 M6\nG43 H2\nG0 X0 Y0 Z1\nG1 Z0 F100\n"
      "G5.1 X4 Y0 I2 J2\nG0 Z1\nM30\n";
  const P2 p0{0, 0}, p1{2, 2}, p2{4, 0};
  expect_on_curve(program, quadratic_bezier(p0, p1, p2), p2);
}

TEST(RewriteSplines, ACubicSplineIsWrittenAsCorrectedChordsOfItsCurve) {
  const std::string program =
      "G21 G90 G94\n(OPERATION: FACE)\nT2 M6\nG43 H2\nG0 X0 Y0 Z1\nG1 Z0 F100\n"
      "G5 X4 Y0 I1 J2 P-1 Q2\nG0 Z1\nM30\n";
  const P2 p0{0, 0}, p1{1, 2}, p2{3, 2}, p3{4, 0};
  expect_on_curve(
      program,
      [&](double t) {
        const double u = 1 - t;
        const double a = u * u * u, b = 3 * t * u * u, c = 3 * t * t * u, d = t * t * t;
        return P2{a * p0[0] + b * p1[0] + c * p2[0] + d * p3[0],
                  a * p0[1] + b * p1[1] + c * p2[1] + d * p3[1]};
      },
      p3);
}

std::string error_of(const std::string& program) {
  try {
    rewrite_program(program, "bad.ngc", constant_matrix(), options());
  } catch (const GcodeError& e) {
    return e.what();
  }
  return "accepted";
}

TEST(RewriteSplines, SplinesOutsideTheOperationAreCopiedOrRefusedByName) {
  // Outside the operation, after an uncorrected rapid: copied as written.
  const std::string outside =
      "G21 G90 G94\nT2 M6\nG43 H2\n(OPERATION: FACE)\nG0 X0 Y0 Z1\nG1 Z0 F100\nG1 X2\n"
      "G0 Z1\n(OPERATION: OTHER)\nG0 X0 Y0\nG1 Z0\nG5.1 X4 Y0 I2 J2\nG0 Z5\nM30\n";
  const RewriteResult r = rewrite_program(outside, "s.ngc", constant_matrix(), options());
  EXPECT_NE(r.text.find("\nG5.1 X4 Y0 I2 J2\n"), std::string::npos) << r.text;
  // Right after a corrected move it would start from the corrected point: a
  // G1 back to the original one is written before it, the spline kept.
  const std::string displaced =
      "G21 G90 G94\nT2 M6\nG43 H2\n(OPERATION: FACE)\nG0 X0 Y0 Z1\nG1 Z0 F100\nG1 X2\n"
      "(OPERATION: OTHER)\nG5.1 X4 Y0 I2 J2\nG0 Z5\nM30\n";
  const RewriteResult d = rewrite_program(displaced, "s.ngc", constant_matrix(), options());
  EXPECT_NE(d.text.find("\nG1 X2 Y0 Z0\nG5.1 X4 Y0 I2 J2\n"), std::string::npos) << d.text;
  const CanonProgram again = Interpreter(options().interpreter).run_text(d.text, "s.ngc");
  const NurbsFeed* spline = nullptr;
  for (const CanonCall& c : again.calls)
    if (const auto* n = std::get_if<NurbsFeed>(&c.op)) spline = n;
  ASSERT_NE(spline, nullptr) << d.text;
  ASSERT_EQ(spline->points.size(), 3u);
  // Its control points as the words give them: start (2, 0), start + (I, J), end.
  const std::array<P2, 3> want{P2{2, 0}, P2{4, 2}, P2{4, 0}};
  for (size_t k = 0; k < 3; ++k) {
    EXPECT_NEAR(spline->points[k].x, want[k][0], 1e-12) << k;
    EXPECT_NEAR(spline->points[k].y, want[k][1], 1e-12) << k;
  }
  // A NURBS block there cannot have a move written into it.
  const std::string block =
      "G21 G90 G94\nT2 M6\nG43 H2\n(OPERATION: FACE)\nG0 X0 Y0 Z1\nG1 Z0 F100\nG1 X2\n"
      "(OPERATION: OTHER)\nG5.2 X2 Y1 P1 L3\nX3 Y2 P1\nX4 Y0 P1\nG5.3\nG0 Z5\nM30\n";
  const std::string e = error_of(block);
  EXPECT_NE(e.find("G5.2 NURBS block right after a corrected move"), std::string::npos) << e;
}

// A NURBS block of the operation spans several lines: they are replaced by
// the corrected chords of its curve. The tool's position and two control
// points of weight 1, order 3 (LinuxCNC's knots 0 0 0 1 1 1), make a
// quadratic Bezier curve.
TEST(RewriteSplines, ANurbsBlockIsWrittenOutAsCorrectedChordsInPlaceOfItsLines) {
  const std::string program =
      "G21 G90 G94\n(OPERATION: FACE)\nT2 M6\nG43 H2\nG0 X0 Y0 Z1\nG1 Z0 F100\n"
      "G5.2 X2 Y2 P1 L3\nX4 Y0 P1\nG5.3\nG0 Z1\nM30\n";
  const P2 p0{0, 0}, p1{2, 2}, p2{4, 0};
  expect_on_curve(
      program, quadratic_bezier(p0, p1, p2), p2,
      "(truecut rewrite: lines 7-9, the NURBS block G5.2 ... G5.3, written out as the ");
  const RewriteResult r = rewrite_program(program, "s.ngc", constant_matrix(), options());
  EXPECT_EQ(r.text.find("\nG5.2"), std::string::npos) << r.text;
  // The rapid after it leaves the corrected end with all of X Y Z.
  EXPECT_NE(r.text.find("\nG0 X4 Y0 Z1\nM30\n"), std::string::npos) << r.text;
}

}  // namespace
}  // namespace truecut::interp
