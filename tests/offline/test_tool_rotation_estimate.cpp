// The tool rotation estimated from compensation vectors along a flank
// (offline/tool_rotation.hpp, issue 19 point 6). Planted cases: a wall cut by
// the flank of a tool whose needed correction changes linearly with the
// height above the tip; the oracle is the planted slope and the flank
// displacement a rotation about the tip gives (w x (h k) = b h n), written
// out here.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <vector>

#include "truecut/offline/tool_rotation.hpp"

using namespace truecut::offline;
using Eigen::Vector3d;

namespace {

// Points on a wall with unit normal n, at heights 0..height_mm above the tip
// of sample `sample` (axis k), all needing a + b h along n (+ noise).
void add_wall(std::vector<PlacedVector>& out, std::uint32_t sample, const Vector3d& tip,
              const Vector3d& k, const Vector3d& n, double a_mm, double b_per_mm, double height_mm,
              int count, double noise_mm = 0.0, unsigned seed = 1) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (int i = 0; i < count; ++i) {
    const double h = height_mm * i / (count - 1);
    PlacedVector p;
    p.sample = sample;
    p.tcp_mm = tip;
    p.axis = k;
    p.point_mm = tip + h * k + 1.0 * n;  // on the wall, the tool's radius away
    p.normal = n;
    p.vector_mm = (a_mm + b_per_mm * h + noise_mm * noise(rng)) * n;
    out.push_back(p);
  }
}

// The estimate's geometry on its own: a machine that gives every tilt, and
// every slope used however small.
ToolRotationOptions any_tilt() {
  ToolRotationOptions o;
  o.kinematics = RotaryKinematics::kAnyOrientation;
  o.min_slope_significance = 0.0;
  return o;
}

// The tool axis of a table-table A/C machine in the workpiece frame
// (docs/offline.md, tool_path.hpp), written out here, and its turns by
// central differences.
Vector3d axis_at(double a_rad, double c_rad) {
  return {std::sin(a_rad) * std::sin(c_rad), std::sin(a_rad) * std::cos(c_rad), std::cos(a_rad)};
}

}  // namespace

TEST(ToolRotationEstimate, ALinearTrendAlongTheFlankBecomesARotationAboutTheTip) {
  // A vertical tool on walls facing +x, -y and a tilted tool on a tilted wall.
  struct Case {
    Vector3d k, n;
  } cases[] = {{Vector3d::UnitZ(), Vector3d::UnitX()},
               {Vector3d::UnitZ(), -Vector3d::UnitY()},
               {Vector3d(0, std::sin(0.5), std::cos(0.5)), Vector3d(1, 0, 0)}};
  for (const Case& c : cases) {
    for (const double b : {-7e-4, 3e-4, 1.2e-3}) {
      std::vector<PlacedVector> placed;
      add_wall(placed, 4, Vector3d(1, 2, 3), c.k, c.n, 0.03, b, 16.0, 40);
      const ToolRotationEstimate e = estimate_tool_rotation(placed, any_tilt());
      ASSERT_EQ(1u, e.rotations.size());
      EXPECT_EQ(1, e.tilted_samples);
      const Vector3d w = e.rotations[0].vector_mm;
      EXPECT_EQ(Vector3d(1, 2, 3), e.rotations[0].position_mm);
      // The flank at height h moves by w x (h k): b h along n.
      for (const double h : {1.0, 8.0, 16.0}) {
        const Vector3d moved = w.cross(h * c.k);
        EXPECT_NEAR(0.0, (moved - b * h * c.n).norm(), 1e-12) << b << " h " << h;
      }
      EXPECT_NEAR(0.0, w.dot(c.k), 1e-15) << "no turn about the tool's own axis";
      // What is left for the tip: a, whatever the height.
      for (const Vector3d& t : e.translations_mm)
        EXPECT_NEAR(0.0, (t - 0.03 * c.n).norm(), 1e-12);
    }
  }
}

TEST(ToolRotationEstimate, NoRotationWithoutHeightOrOnACorner) {
  std::vector<PlacedVector> placed;
  // Sample 1: a face cut by the tip (all points at h = 0).
  add_wall(placed, 1, Vector3d(0, 0, 0), Vector3d::UnitZ(), Vector3d::UnitX(), 0.02, 0.0, 0.0, 5);
  for (int i = 0; i < 5; ++i)
    placed[placed.size() - 1 - i].vector_mm = Vector3d(0.02 + 0.001 * i, 0, 0);
  // Sample 2: a slope on 0.5 mm of height only (below the 1 mm spread).
  add_wall(placed, 2, Vector3d(5, 0, 0), Vector3d::UnitZ(), Vector3d::UnitX(), 0.0, 1e-3, 0.5, 6);
  // Sample 3: a corner, two walls 90 degrees apart.
  add_wall(placed, 3, Vector3d(9, 0, 0), Vector3d::UnitZ(), Vector3d::UnitX(), 0.0, 1e-3, 10.0, 6);
  add_wall(placed, 3, Vector3d(9, 0, 0), Vector3d::UnitZ(), Vector3d::UnitY(), 0.0, 1e-3, 10.0, 6);
  // Sample 4: two points only.
  add_wall(placed, 4, Vector3d(12, 0, 0), Vector3d::UnitZ(), Vector3d::UnitX(), 0.0, 1e-3, 10.0, 2);
  const ToolRotationEstimate e = estimate_tool_rotation(placed);
  ASSERT_EQ(4u, e.rotations.size());
  EXPECT_EQ(0, e.tilted_samples);
  for (const FitSample& r : e.rotations)
    EXPECT_EQ(Vector3d::Zero(), r.vector_mm) << r.position_mm.transpose();
  for (std::size_t i = 0; i < placed.size(); ++i)
    EXPECT_EQ(placed[i].vector_mm, e.translations_mm[i]) << i;
}

TEST(ToolRotationEstimate, NoiseLeavesTheSlopeWithinItsStandardError) {
  // 40 points over 16 mm, sigma 5 um: the slope's standard error is
  // sigma / sqrt(sum (h - mean)^2) = 5e-3 / sqrt(40 * 16^2 / 12 * (41/39)) mm/mm.
  const double sigma = 5e-3, b = 6e-4;
  const double se = sigma / std::sqrt(40.0 * 16.0 * 16.0 / 12.0 * 41.0 / 39.0);
  int within_3se = 0;
  for (unsigned seed = 1; seed <= 50; ++seed) {
    std::vector<PlacedVector> placed;
    add_wall(placed, 0, Vector3d::Zero(), Vector3d::UnitZ(), Vector3d::UnitX(), 0.02, b, 16.0, 40,
             sigma, seed);
    const ToolRotationEstimate e = estimate_tool_rotation(placed, any_tilt());
    const double got = e.rotations[0].vector_mm.cross(Vector3d::UnitZ()).dot(Vector3d::UnitX());
    if (std::abs(got - b) <= 3.0 * se) ++within_3se;
  }
  // 99.7 % within 3 standard errors: at most 1 of 50 outside by chance.
  EXPECT_GE(within_3se, 49);
}

TEST(RealisableRotation, ATableTableMachineTiltsAlongAAndSidewaysOnlyOnceATiltsTheTable) {
  const double h = 1e-6;
  for (const double a_deg : {0.0, 1.0, 3.0, 30.0, -45.0}) {
    for (const double c_deg : {0.0, 90.0, -135.0, 20.0}) {
      const double a = a_deg * M_PI / 180.0, c = c_deg * M_PI / 180.0;
      const Vector3d k = axis_at(a, c);
      const Vector3d along_a = (axis_at(a + h, c) - axis_at(a - h, c)) / (2 * h);
      const Vector3d along_c = (axis_at(a, c + h) - axis_at(a, c - h)) / (2 * h);
      // C turns the axis sideways by sin A per radian; below sin 2 deg the
      // component would damp that away, so the field must not ask for it.
      const bool sideways = along_c.norm() >= std::sin(2.0 * M_PI / 180.0);
      for (const Vector3d& w :
           {Vector3d(4e-4, 0, 0), Vector3d(0, -7e-4, 0), Vector3d(2e-4, 3e-4, 5e-4)}) {
        const Vector3d dk = w.cross(k);
        const Vector3d want_a = dk.dot(along_a.normalized()) * along_a.normalized();
        const Vector3d want_c = along_c.norm() > 1e-9
                                    ? Vector3d(dk.dot(along_c.normalized()) * along_c.normalized())
                                    : Vector3d::Zero();
        const Vector3d kept_tilt = want_a + (sideways ? want_c : Vector3d::Zero());
        const Vector3d got = realisable_rotation(w, k, c_deg, RotaryKinematics::kAcTableTable);
        SCOPED_TRACE(testing::Message()
                     << "A " << a_deg << " C " << c_deg << " w " << w.transpose());
        EXPECT_NEAR(0.0, (got.cross(k) - kept_tilt).norm(), 1e-9);
        EXPECT_NEAR(0.0, got.dot(k), 1e-15);
        // A machine with every tilt keeps the whole tilt.
        const Vector3d any = realisable_rotation(w, k, c_deg, RotaryKinematics::kAnyOrientation);
        EXPECT_NEAR(0.0, (any.cross(k) - dk).norm(), 1e-15);
      }
    }
  }
}

TEST(ToolRotationEstimate, ATiltTheMachineCannotGiveLeavesTheMeanShiftOfTheFlank) {
  // A standing tool (A = 0, C = 0) on a wall facing +x would need a tilt
  // towards x: only C could give it, and C does nothing at A = 0. The same
  // tool on a wall facing -y tilts along A.
  for (const bool facing_x : {true, false}) {
    const Vector3d n = facing_x ? Vector3d(1, 0, 0) : Vector3d(0, -1, 0);
    const double a = 0.03, b = 8e-4, height = 16.0;
    std::vector<PlacedVector> placed;
    add_wall(placed, 0, Vector3d::Zero(), Vector3d::UnitZ(), n, a, b, height, 41);
    const ToolRotationEstimate e = estimate_tool_rotation(placed);  // the default: A/C table
    ASSERT_EQ(1u, e.rotations.size());
    EXPECT_EQ(1, e.tilted_samples);
    EXPECT_EQ(facing_x ? 1 : 0, e.cut_samples);
    if (facing_x) {
      EXPECT_EQ(Vector3d::Zero(), e.rotations[0].vector_mm);
      EXPECT_NEAR(b * Vector3d::UnitZ().cross(n).norm(), e.max_left_out_rad, 1e-15);
      // No rotation: each point keeps its own vector, and their mean, the
      // flank's best constant shift, is a + b h_mean.
      Vector3d mean = Vector3d::Zero();
      for (std::size_t i = 0; i < placed.size(); ++i) {
        EXPECT_EQ(placed[i].vector_mm, e.translations_mm[i]);
        mean += e.translations_mm[i] / double(placed.size());
      }
      EXPECT_NEAR(0.0, (mean - (a + b * height / 2) * n).norm(), 1e-12);
    } else {
      for (const Vector3d& t : e.translations_mm)
        EXPECT_NEAR(0.0, (t - a * n).norm(), 1e-12);
    }
  }
}

TEST(ToolRotationEstimate, ASlopeWithinTheScansCorrelatedNoiseGivesNoRotation) {
  // 100 points over 16 mm with no trend, their error an AR(1) series along
  // the flank (rho 0.7, stationary sigma 20 um): a scan whose error is
  // correlated over its mesh's facets. Treated as independent, the slope's
  // standard error would be sqrt(1.7 / 0.3) = 2.4 times too small, and one
  // flank in five would show a "significant" tilt at three of them.
  const int n = 100;
  const double rho = 0.7, sigma = 0.02;
  ToolRotationOptions three_se;
  three_se.min_slope_significance = 3.0;
  int tilted = 0;
  for (unsigned seed = 1; seed <= 200; ++seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> g(0.0, 1.0);
    std::vector<PlacedVector> placed;
    add_wall(placed, 0, Vector3d::Zero(), Vector3d::UnitZ(), -Vector3d::UnitY(), 0.03, 0.0, 16.0,
             n);
    double e = sigma * g(rng);
    for (PlacedVector& p : placed) {
      p.vector_mm += e * p.normal;
      e = rho * e + std::sqrt(1 - rho * rho) * sigma * g(rng);
    }
    const ToolRotationEstimate est = estimate_tool_rotation(placed, three_se);
    tilted += est.tilted_samples;
    EXPECT_EQ(est.tilted_samples + est.insignificant_samples, 1);
  }
  // At three standard errors 0.27 % would pass by chance; the correlation
  // is estimated from the same 100 points, so allow 2 %.
  EXPECT_LE(tilted, 4);

  // A trend of 20 um over the same flank under noise of 4 um (the slope six
  // of its standard errors) is kept.
  int kept = 0;
  for (unsigned seed = 1; seed <= 50; ++seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> g(0.0, 1.0);
    std::vector<PlacedVector> placed;
    add_wall(placed, 0, Vector3d::Zero(), Vector3d::UnitZ(), -Vector3d::UnitY(), 0.03, 0.02 / 16.0,
             16.0, n);
    double e = 0.2 * sigma * g(rng);
    for (PlacedVector& p : placed) {
      p.vector_mm += e * p.normal;
      e = rho * e + std::sqrt(1 - rho * rho) * 0.2 * sigma * g(rng);
    }
    kept += estimate_tool_rotation(placed, three_se).tilted_samples;
  }
  EXPECT_GE(kept, 49);
}
