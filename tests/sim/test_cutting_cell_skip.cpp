// A tool instance skips the grid cells whose lines cannot meet the tool
// (detail::box_misses_tool): the test must never call a box empty that holds a
// point of the tool, or the skipped dexels would keep material the tool cuts.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "../../sim/cutting/tool_solid.hpp"

using truecut::sim::cutting::detail::box_misses_tool;
using truecut::sim::cutting::detail::ToolGeometry;

namespace {

// Whether x (relative to the tip) lies in the tool grown by `grow_mm`.
bool inside_tool(const Eigen::Vector3d& x, const Eigen::Vector3d& a, const ToolGeometry& g,
                 double grow_mm) {
  const double w = x.dot(a);
  const double r = (x - w * a).norm();
  if (w > g.flute_mm + grow_mm) return false;
  if (w >= g.corner_mm) return r <= g.radius_mm + grow_mm;
  // The rounded bottom: within rc of the core disk of radius R − rc at w = rc.
  const double dr = std::max(0.0, r - g.core_mm), dw = g.corner_mm - w;
  return std::hypot(dr, dw) <= g.corner_mm + grow_mm;
}

ToolGeometry tool(double radius_mm, double corner_mm, double flute_mm) {
  return {radius_mm, corner_mm, radius_mm - corner_mm, flute_mm};
}

}  // namespace

TEST(CuttingCellSkip, ABoxCalledEmptyHoldsNoPointOfTheTool) {
  const ToolGeometry tools[] = {tool(3, 3, 15), tool(5, 0, 20), tool(4, 1, 12), tool(1, 0, 8)};
  std::mt19937_64 rng(25);
  std::uniform_real_distribution<double> unit(-1, 1), size(0.05, 4);
  int skipped = 0, kept = 0;
  for (const ToolGeometry& g : tools) {
    for (int k = 0; k < 4000; ++k) {
      Eigen::Vector3d a(unit(rng), unit(rng), unit(rng));
      if (a.norm() < 0.1) continue;
      a.normalize();
      if (k % 4 == 0) a = Eigen::Vector3d::UnitZ();  // the 3-axis case, axis-aligned
      const Eigen::Vector3d centre =
          Eigen::Vector3d(unit(rng), unit(rng), unit(rng)) * (g.radius_mm + 3) +
          (0.5 + 0.7 * unit(rng)) * g.flute_mm * a;
      const Eigen::Vector3d half(size(rng), size(rng), size(rng));
      const Eigen::Vector3d lo = centre - half, hi = centre + half;
      if (!box_misses_tool(lo, hi, a, g)) {
        ++kept;
        continue;
      }
      ++skipped;
      // Every point of a 9³ lattice over the box (faces, edges and corners
      // included) lies outside the tool grown by 0.5 µm.
      for (int i = 0; i <= 8; ++i)
        for (int j = 0; j <= 8; ++j)
          for (int l = 0; l <= 8; ++l) {
            const Eigen::Vector3d x = lo + Eigen::Vector3d(i, j, l).cwiseProduct(hi - lo) / 8;
            ASSERT_FALSE(inside_tool(x, a, g, 5e-4))
                << "tool R " << g.radius_mm << " rc " << g.corner_mm << " axis " << a.transpose()
                << ", box " << lo.transpose() << " .. " << hi.transpose() << ", point "
                << x.transpose();
          }
    }
  }
  // Not vacuous: both answers occur often.
  EXPECT_GT(skipped, 3000);
  EXPECT_GT(kept, 3000);
}

TEST(CuttingCellSkip, ABoxTouchingTheToolIsKeptAndOneJustAwayIsSkipped) {
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d tiny(0.1, 0.1, 0.1);
  // Ball R3: its lowest point is the tip; beside the flank at w = 5.
  const ToolGeometry ball = tool(3, 3, 15);
  EXPECT_FALSE(
      box_misses_tool(Eigen::Vector3d(-0.1, -0.1, -0.2), Eigen::Vector3d(0.1, 0.1, 0), z, ball));
  EXPECT_TRUE(box_misses_tool(Eigen::Vector3d(-0.1, -0.1, -0.2), Eigen::Vector3d(0.1, 0.1, -1e-3),
                              z, ball));
  const Eigen::Vector3d flank(3, 0, 5);
  EXPECT_FALSE(box_misses_tool(flank, flank + tiny, z, ball));
  EXPECT_TRUE(box_misses_tool(flank + Eigen::Vector3d(1e-3, 0, 0), flank + tiny, z, ball));
  EXPECT_TRUE(box_misses_tool(flank + Eigen::Vector3d(1e-3, 0, 0),
                              flank + Eigen::Vector3d(0.1, 0, 0.1), z, ball));
  EXPECT_TRUE(box_misses_tool(flank + Eigen::Vector3d(0.2, 0, 0),
                              flank + Eigen::Vector3d(0.2, 0, 0) + tiny, z, ball));
  // Ball: a box below the cylinder's start (w < rc) but touching the sphere.
  const Eigen::Vector3d side(3, 0, 3);  // the sphere's equator
  EXPECT_FALSE(box_misses_tool(side - tiny, side, z, ball));
  // ... and one just above the equator, outside the sphere, on the cylinder.
  EXPECT_FALSE(
      box_misses_tool(Eigen::Vector3d(3, 0, 3.05), Eigen::Vector3d(3.1, 0.1, 3.15), z, ball));
  // Flat end mill R5: the corner of its bottom, and just below it.
  const ToolGeometry flat = tool(5, 0, 20);
  const Eigen::Vector3d rim(5, 0, 0);
  EXPECT_FALSE(box_misses_tool(rim, rim + tiny, z, flat));
  EXPECT_TRUE(box_misses_tool(rim - tiny - Eigen::Vector3d(0, 0, 1e-3),
                              rim - Eigen::Vector3d(0, 0, 1e-3), z, flat));
  // The top of the flutes, tilted 45° about y.
  const Eigen::Vector3d a = Eigen::Vector3d(1, 0, 1).normalized();
  const Eigen::Vector3d top = 20 * a;
  EXPECT_FALSE(box_misses_tool(top, top + tiny, a, flat));
  EXPECT_TRUE(box_misses_tool(top + 1e-3 * a, top + 1e-3 * a + tiny, a, flat));
}
