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
      const ToolRotationEstimate e = estimate_tool_rotation(placed);
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
    const ToolRotationEstimate e = estimate_tool_rotation(placed);
    const double got = e.rotations[0].vector_mm.cross(Vector3d::UnitZ()).dot(Vector3d::UnitX());
    if (std::abs(got - b) <= 3.0 * se) ++within_3se;
  }
  // 99.7 % within 3 standard errors: at most 1 of 50 outside by chance.
  EXPECT_GE(within_3se, 49);
}
