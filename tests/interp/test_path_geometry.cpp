// path_geometry: lines, arcs and helices in the three planes, both
// directions, full circles and P turns, checked against formulas written
// out here (a circle c + R cos θ e1 + R sin θ e2 + h n in each plane's own
// basis), against the sum of fine chords, and for the chord tolerance and
// largest step of the sampling.
#include "truecut/interp/path_geometry.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <variant>

#include "interp_test_util.hpp"

namespace truecut::interp::testing {
namespace {

namespace pg = path_geometry;
using P3 = pg::Point3;
constexpr double kPi = std::numbers::pi;

// Each plane's basis as G17/G18/G19 define it: the arc turns from e1 towards
// e2 counter-clockwise (G3) seen from the tip of n.
struct Basis {
  Plane plane;
  P3 e1, e2, n;
};
const Basis kBases[] = {
    {Plane::kXY, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}},
    {Plane::kXZ, {0, 0, 1}, {1, 0, 0}, {0, 1, 0}},
    {Plane::kYZ, {0, 1, 0}, {0, 0, 1}, {1, 0, 0}},
};

double dot(const P3& a, const P3& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
P3 add(const P3& a, const P3& b, double k = 1) {
  return {a[0] + k * b[0], a[1] + k * b[1], a[2] + k * b[2]};
}
double dist(const P3& a, const P3& b) {
  return std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
}
// Distance from p to the segment ab.
double to_segment(const P3& p, const P3& a, const P3& b) {
  const P3 ab = add(b, a, -1), ap = add(p, a, -1);
  const double l2 = dot(ab, ab);
  const double t = l2 > 0 ? std::clamp(dot(ap, ab) / l2, 0.0, 1.0) : 0.0;
  return dist(p, add(a, ab, t));
}

// A helix written out: centre c (a point of the plane through the start),
// radius R, start angle alpha, signed sweep sigma, rise h along n.
struct Written {
  Basis b;
  P3 c;
  double R, alpha, sigma, h;
  P3 at(double f) const {
    const double th = alpha + sigma * f;
    P3 p = add(c, b.e1, R * std::cos(th));
    p = add(p, b.e2, R * std::sin(th));
    return add(p, b.n, h * f);
  }
  double length() const { return std::sqrt(R * sigma * R * sigma + h * h); }
  P3 tangent(double f) const {
    const double th = alpha + sigma * f;
    P3 d = add(add(P3{0, 0, 0}, b.e1, -R * sigma * std::sin(th)), b.e2, R * sigma * std::cos(th));
    d = add(d, b.n, h);
    const double l = std::sqrt(dot(d, d));
    return {d[0] / l, d[1] / l, d[2] / l};
  }
  // The module's view of it: ends and the centre's plane coordinates.
  pg::Helix helix(int rotation) const {
    return pg::helix_through(b.plane, at(0), at(1), dot(c, b.e1), dot(c, b.e2), rotation);
  }
};

TEST(PathGeometry, PlaneAxesFollowCanonicalArcFeedOrder) {
  for (const Basis& b : kBases) {
    const pg::PlaneAxes a = pg::plane_axes(b.plane);
    EXPECT_EQ(1.0, b.e1[a.first]);
    EXPECT_EQ(1.0, b.e2[a.second]);
    EXPECT_EQ(1.0, b.n[a.normal]);
    // Right-handed: e1 x e2 = n.
    const P3 x{b.e1[1] * b.e2[2] - b.e1[2] * b.e2[1], b.e1[2] * b.e2[0] - b.e1[0] * b.e2[2],
               b.e1[0] * b.e2[1] - b.e1[1] * b.e2[0]};
    EXPECT_EQ(b.n, x);
  }
}

TEST(PathGeometry, SweptAngleBothDirectionsFullCirclesAndTurns) {
  EXPECT_NEAR(kPi / 2, pg::swept_angle_rad(0, kPi / 2, 1), 1e-15);
  EXPECT_NEAR(-3 * kPi / 2, pg::swept_angle_rad(0, kPi / 2, -1), 1e-15);
  EXPECT_NEAR(3 * kPi / 2, pg::swept_angle_rad(kPi / 2, 0, 1), 1e-15);
  EXPECT_NEAR(-kPi / 2, pg::swept_angle_rad(kPi / 2, 0, -1), 1e-15);
  // Across the ±π cut.
  EXPECT_NEAR(kPi / 2, pg::swept_angle_rad(3 * kPi / 4, -3 * kPi / 4, 1), 1e-15);
  EXPECT_NEAR(-kPi / 2, pg::swept_angle_rad(-3 * kPi / 4, 3 * kPi / 4, -1), 1e-15);
  // Same direction (and within 1e-12): a full turn.
  EXPECT_EQ(2 * kPi, pg::swept_angle_rad(0.3, 0.3, 1));
  EXPECT_EQ(-2 * kPi, pg::swept_angle_rad(0.3, 0.3, -1));
  EXPECT_NEAR(2 * kPi, pg::swept_angle_rad(0.3, 0.3 + 1e-13, 1), 1e-12);
  EXPECT_NEAR(-2 * kPi, pg::swept_angle_rad(0.3, 0.3 - 1e-13, -1), 1e-12);
  // P turns: |rotation| - 1 extra full turns.
  EXPECT_NEAR(kPi / 2 + 4 * kPi, pg::swept_angle_rad(0, kPi / 2, 3), 1e-14);
  EXPECT_NEAR(-3 * kPi / 2 - 2 * kPi, pg::swept_angle_rad(0, kPi / 2, -2), 1e-14);
  EXPECT_NEAR(6 * kPi, pg::swept_angle_rad(1, 1, 3), 1e-14);
}

// Arcs and helices in every plane, both directions, with and without extra
// turns: sweep, length, points, tangents against the written-out helix.
TEST(PathGeometry, HelicesInEveryPlaneMatchTheWrittenFormula) {
  struct Case {
    double alpha, sigma, h;
    int rotation;
  };
  const Case cases[] = {
      {0.3, 1.2, 0, 1},                       // G3 arc
      {0.3, -1.2, 0, -1},                     // G2 arc
      {2.9, 0.7, 0, 1},                       // across the ±π cut
      {-2.0, -2.5, 4.0, -1},                  // G2 helix
      {1.0, 2 * kPi, 0, 1},                   // G3 full circle
      {1.0, -2 * kPi, -3.0, -1},              // G2 full helical turn
      {0.5, 1.5 + 2 * 2 * kPi, 6.0, 3},       // G3 P3
      {0.5, -(1.5 + 1 * 2 * kPi), -2.0, -2},  // G2 P2
      {-1.0, 4 * kPi, 1.0, 2},                // G3 P2, ends on the start
  };
  for (const Basis& b : kBases) {
    for (const Case& k : cases) {
      SCOPED_TRACE(::testing::Message() << "plane " << static_cast<int>(b.plane) << " alpha "
                                        << k.alpha << " sigma " << k.sigma);
      const Written w{b, {3.0, -7.0, 11.0}, 25.0, k.alpha, k.sigma, k.h};
      const pg::Helix h = w.helix(k.rotation);
      EXPECT_NEAR(k.sigma, h.arc.sweep_rad, 1e-12);
      EXPECT_NEAR(25.0, h.arc.start_radius_mm, 1e-12);
      EXPECT_NEAR(25.0, h.arc.end_radius_mm, 1e-12);
      EXPECT_NEAR(w.length(), pg::length_mm(h), 1e-11);
      EXPECT_NEAR(w.length(), pg::helix_length_mm(25.0, h.arc.sweep_rad, k.h), 1e-11);
      for (double f : {0.0, 0.125, 0.5, 0.77, 1.0}) {
        const P3 p = pg::point_at(h, f), q = w.at(f);
        EXPECT_LT(dist(p, q), 1e-11) << "f " << f;
        const P3 t = pg::tangent_at(h, f), u = w.tangent(f);
        EXPECT_LT(dist(t, u), 1e-12) << "f " << f;
        // At arc length: constant speed, so s = f * length.
        EXPECT_LT(dist(pg::point_at_length(h, f * w.length()), q), 1e-11) << "f " << f;
      }
    }
  }
}

// The length against the sum of many short chords of the same curve.
TEST(PathGeometry, LengthIsTheLimitOfFineChords) {
  for (const Basis& b : kBases) {
    for (int rotation : {1, -1, 2, -3}) {
      const double sigma =
          rotation > 0 ? 2.2 + 2 * kPi * (rotation - 1) : -(2.2 + 2 * kPi * (-rotation - 1));
      const Written w{b, {-4.0, 1.0, 2.0}, 7.5, -0.4, sigma, 3.3};
      const pg::Helix h = w.helix(rotation);
      constexpr int kN = 200000;
      double chords = 0;
      P3 prev = w.at(0);
      for (int i = 1; i <= kN; ++i) {
        const P3 p = w.at(static_cast<double>(i) / kN);
        chords += dist(p, prev);
        prev = p;
      }
      // A chord of angle φ falls short of its arc by about R φ³ / 24.
      EXPECT_NEAR(chords, pg::length_mm(h), 1e-8 * chords);
    }
  }
}

TEST(PathGeometry, SpiralRadiusIsLinearInTheAngle) {
  // Start radius 10 at angle 0, end radius 10.02 at angle π/2 (XY, G3).
  const pg::Helix h = pg::helix_through(Plane::kXY, {10, 0, 0}, {0, 10.02, 0}, 0, 0, 1);
  EXPECT_NEAR(kPi / 2, h.arc.sweep_rad, 1e-15);
  EXPECT_NEAR(0.5 * (10 + 10.02) * kPi / 2, pg::length_mm(h), 1e-12);
  const P3 mid = pg::point_at(h, 0.5);
  EXPECT_NEAR(10.01 * std::cos(kPi / 4), mid[0], 1e-12);
  EXPECT_NEAR(10.01 * std::sin(kPi / 4), mid[1], 1e-12);
}

TEST(PathGeometry, LinesHaveTheirEuclideanGeometry) {
  const pg::Line l{{1, 2, 3}, {4, -2, 15}};
  EXPECT_NEAR(13.0, pg::length_mm(l), 1e-14);
  const P3 p = pg::point_at(l, 0.25);
  EXPECT_NEAR(1.75, p[0], 1e-15);
  EXPECT_NEAR(1.0, p[1], 1e-15);
  EXPECT_NEAR(6.0, p[2], 1e-15);
  EXPECT_LT(dist(pg::point_at_length(l, 6.5), P3{2.5, 0, 9}), 1e-14);
  EXPECT_LT(dist(pg::tangent_at(l, 0.3), P3{3.0 / 13, -4.0 / 13, 12.0 / 13}), 1e-15);
  const std::vector<P3> s = pg::sample(l, 2.0);
  ASSERT_EQ(8u, s.size());  // ceil(13 / 2) = 7 pieces
  EXPECT_EQ(l.start_mm, s.front());
  EXPECT_EQ(l.end_mm, s.back());
  for (size_t i = 1; i < s.size(); ++i)
    EXPECT_LE(dist(s[i], s[i - 1]), 2.0 + 1e-12);
}

// Every chord of the sampling lies within the tolerance of the curve it
// replaces, and one piece fewer would not.
TEST(PathGeometry, SamplingHonoursTheChordTolerance) {
  for (const Basis& b : kBases) {
    for (int rotation : {1, -1, -2}) {
      for (double tol : {0.1, 0.01, 0.001}) {
        const double sigma = rotation > 0 ? 2.6 : -(2.6 + 2 * kPi * (-rotation - 1));
        const Written w{b, {5.0, 5.0, -1.0}, 12.0, 0.8, sigma, 1.5};
        const pg::Helix h = w.helix(rotation);
        const std::vector<P3> s = pg::sample(h, tol, 0);
        const int n = static_cast<int>(s.size()) - 1;
        ASSERT_GE(n, 1);
        // The sagitta of n equal pieces, and of n - 1.
        EXPECT_LE(12.0 * (1 - std::cos(std::abs(sigma) / (2 * n))), tol);
        if (n > 1) {
          EXPECT_GT(12.0 * (1 - std::cos(std::abs(sigma) / (2 * (n - 1)))), tol);
        }
        double worst = 0;
        for (int k = 0; k < n; ++k) {
          EXPECT_LT(dist(s[k], w.at(static_cast<double>(k) / n)), 1e-11);
          for (int j = 1; j < 64; ++j) {
            const P3 p = w.at((k + j / 64.0) / n);
            worst = std::max(worst, to_segment(p, s[k], s[k + 1]));
          }
        }
        EXPECT_LE(worst, tol + 1e-12) << "n " << n;
        EXPECT_GT(worst, 0.5 * tol);  // not needlessly fine
      }
    }
  }
  // A step limit on top of the tolerance: no piece longer than the step.
  const Written w{kBases[1], {0, 0, 0}, 50.0, 0, -kPi, 0};
  const pg::Helix h = w.helix(-1);
  const std::vector<P3> s = pg::sample(h, 0.5, 3.0);
  const int n = static_cast<int>(s.size()) - 1;
  EXPECT_EQ(static_cast<int>(std::ceil(50.0 * kPi / 3.0)), n);
  EXPECT_LE(w.length() / n, 3.0);
  // Radius within the tolerance: one piece.
  EXPECT_EQ(1, pg::arc_pieces_for_chord(0.001, 3.0, 0.01));
}

// Moves over more coordinates: the plane pair follows the arc, the others
// (normal axis, rotaries) are linear in the fraction.
TEST(PathGeometry, ArcPointOverSixAxesKeepsOtherAxesLinear) {
  const Axes6 start{0, 10, 0, 0, 0, 0}, end{10, 0, 4, 30, 0, -60};  // XY, G2 about 0
  const pg::PlaneAxes ax = pg::plane_axes(Plane::kXY);
  const pg::PlaneArc a = pg::plane_arc(0, 10, 10, 0, 0, 0, -1);
  EXPECT_NEAR(-kPi / 2, a.sweep_rad, 1e-15);
  const Axes6 p = pg::arc_point_at(ax, a, start, end, 0.5, 6);
  EXPECT_NEAR(10 * std::sqrt(0.5), p.x, 1e-12);
  EXPECT_NEAR(10 * std::sqrt(0.5), p.y, 1e-12);
  EXPECT_NEAR(2.0, p.z, 1e-15);
  EXPECT_NEAR(15.0, p.a, 1e-15);
  EXPECT_NEAR(-30.0, p.c, 1e-15);
}

// The interpreter's arcs: G2/G3 with P in each plane give the rotation and,
// under G93, the feed rate of the written helix length.
TEST(PathGeometry, InterpreterArcsWithTurnsInEveryPlane) {
  struct Case {
    const char* program;
    Plane plane;
    int rotation;
    double length;  // R * sweep with the extra turns, hypot with the rise
  };
  const double quarter = kPi / 2;
  const Case cases[] = {
      // G17: (10,0) -> (0,10) about 0, G3 P2, Z rises 5.
      {"G17 G3 X0 Y10 Z5 I-10 J0 P2", Plane::kXY, 2, std::hypot(10 * (quarter + 2 * kPi), 5.0)},
      // G18: plane (z, x); X10 Z0 -> X0 Z10 about 0: from angle π/2 to 0, G2.
      {"G18 G2 X0 Z10 I-10 K0", Plane::kXZ, -1, 10 * quarter},
      // G19: plane (y, z); Y10 Z0 -> Y10 Z0: a full circle about (0, 0), G3 P3.
      {"G19 G3 Y10 Z0 J-10 K0 P3", Plane::kYZ, 3, 10 * 3 * 2 * kPi},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.program);
    const std::string start = c.plane == Plane::kXY   ? "G0 X10 Y0 Z0\n"
                              : c.plane == Plane::kXZ ? "G0 X10 Y0 Z0\n"
                                                      : "G0 X0 Y10 Z0\n";
    const CanonProgram p = run(std::string("G21 G90 G93\n") + start + c.program + " F2\nM2\n");
    const ArcFeed* arc = nullptr;
    double rate = -1;
    for (const CanonCall& call : p.calls) {
      if (const auto* f = std::get_if<SetFeedRate>(&call.op)) rate = f->units_per_minute;
      if (const auto* a = std::get_if<ArcFeed>(&call.op)) {
        arc = a;
        break;
      }
    }
    ASSERT_NE(nullptr, arc);
    EXPECT_EQ(c.plane, arc->plane);
    EXPECT_EQ(c.rotation, arc->rotation);
    EXPECT_NEAR(c.length * 2, rate, 1e-9);
  }
}

}  // namespace
}  // namespace truecut::interp::testing
