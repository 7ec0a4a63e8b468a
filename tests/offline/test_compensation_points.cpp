#include "offline_geometry_util.hpp"
#include "spatial_check.hpp"
#include "truecut/offline/compensation_points.hpp"
#include "truecut/offline/surfaces.hpp"

#include <gtest/gtest.h>

#include <set>

namespace truecut::offline {
namespace {

// A closed cylinder (radius r, height h) with `segments` facets around.
TriangleMesh cylinder(double r, double h, int segments) {
  TriangleMesh m;
  for (int z = 0; z < 2; ++z) {
    for (int s = 0; s < segments; ++s) {
      const double a = 2 * M_PI * s / segments;
      m.vertices_mm.emplace_back(r * std::cos(a), r * std::sin(a), h * z);
    }
  }
  const auto bottom = static_cast<std::uint32_t>(m.vertices_mm.size());
  m.vertices_mm.emplace_back(0, 0, 0);
  m.vertices_mm.emplace_back(0, 0, h);
  const auto top = bottom + 1;
  const auto n = static_cast<std::uint32_t>(segments);
  for (std::uint32_t s = 0; s < n; ++s) {
    const std::uint32_t s1 = (s + 1) % n;
    m.triangles.push_back({s, s1, n + s1});
    m.triangles.push_back({s, n + s1, n + s});
    m.triangles.push_back({bottom, s1, s});
    m.triangles.push_back({top, n + s, n + s1});
  }
  return m;
}

TEST(Surfaces, BoxSplitsIntoItsSixFaces) {
  const TriangleMesh m = test_geo::box({0, 0, 0}, {30, 20, 10}, 4);
  const std::vector<std::int32_t> ids = segment_surfaces(m);
  EXPECT_EQ(std::set<std::int32_t>(ids.begin(), ids.end()).size(), 6u);
  // Every face's 32 triangles share one id.
  for (std::size_t f = 0; f < 6; ++f) {
    for (std::size_t t = 0; t < 32; ++t)
      EXPECT_EQ(ids[32 * f + t], ids[32 * f]) << "face " << f;
  }
  EXPECT_EQ(ids[0], 0);  // numbered from the lowest triangle
}

TEST(Surfaces, CylinderSideIsOneSurfaceUnderThirtyDegrees) {
  const TriangleMesh m = cylinder(10, 20, 36);  // 10° between side facets
  const std::vector<std::int32_t> ids = segment_surfaces(m, 30.0);
  EXPECT_EQ(std::set<std::int32_t>(ids.begin(), ids.end()).size(), 3u);
  // With a 5° threshold every side facet pair separates.
  const std::vector<std::int32_t> fine = segment_surfaces(m, 5.0);
  EXPECT_EQ(std::set<std::int32_t>(fine.begin(), fine.end()).size(), 36u + 2u);
  const std::vector<std::uint32_t> side =
      triangles_of_surfaces(ids, std::vector<std::int32_t>{ids[0]});
  EXPECT_EQ(side.size(), 72u);
}

TEST(CompensationPoints, VerticesOfSelectedSurfaces) {
  const TriangleMesh m = test_geo::box({0, 0, 0}, {30, 20, 10}, 4);
  const std::vector<std::int32_t> ids = segment_surfaces(m);
  const CompensationPoints all = compensation_points_at_vertices(m, ids);
  EXPECT_EQ(all.size(), m.vertices_mm.size());
  // Top face (+z) only: a 5×5 grid of vertices, interior ones with normal +z.
  const std::int32_t top = ids[5 * 32];
  const CompensationPoints one = compensation_points_at_vertices(m, ids, std::vector{top});
  ASSERT_EQ(one.size(), 25u);
  int interior = 0;
  for (std::size_t i = 0; i < one.size(); ++i) {
    EXPECT_EQ(one.positions_mm[i].z(), 10.0);
    const Eigen::Vector3d& p = one.positions_mm[i];
    if (p.x() > 0 && p.x() < 30 && p.y() > 0 && p.y() < 20) {
      ++interior;
      EXPECT_NEAR((one.normals[i] - Eigen::Vector3d::UnitZ()).norm(), 0.0, 1e-12);
      EXPECT_EQ(one.surface_ids[i], top);
    }
  }
  EXPECT_EQ(interior, 9);
}

TEST(CompensationPoints, EvenSamplingHasTheRequestedSpacing) {
  // Two triangles of very different shape: a sliver and a fat one.
  const TriangleMesh m = test_geo::plate(40, 20, 1, 1, [](double, double) { return 0.0; });
  const std::vector<std::int32_t> ids(m.triangles.size(), 0);
  const double s = 0.5;
  const CompensationPoints c = sample_compensation_points(m, ids, s);
  // About one point per s² of area.
  EXPECT_NEAR(static_cast<double>(c.size()), 40 * 20 / (s * s), 0.05 * 40 * 20 / (s * s));
  const test_spatial::Spacing sp = test_spatial::nearest_spacing(c.positions_mm);
  EXPECT_GT(sp.min_mm, 0.25 * s);
  EXPECT_LT(sp.max_mm, 1.5 * s);
  for (std::size_t i = 0; i < c.size(); ++i) {
    EXPECT_EQ(c.normals[i], Eigen::Vector3d::UnitZ());
    EXPECT_EQ(c.positions_mm[i].z(), 0.0);
  }
  // Deterministic.
  const CompensationPoints again = sample_compensation_points(m, ids, s);
  EXPECT_EQ(again.positions_mm, c.positions_mm);
}

TEST(CompensationPoints, SamplingKeepsSurfacesApart) {
  const TriangleMesh m = test_geo::box({0, 0, 0}, {10, 10, 10}, 2);
  const std::vector<std::int32_t> ids = segment_surfaces(m);
  const CompensationPoints c =
      sample_compensation_points(m, ids, 1.0, std::vector{ids[0], ids[8 * 3]});
  std::set<std::int32_t> seen(c.surface_ids.begin(), c.surface_ids.end());
  EXPECT_EQ(seen, (std::set<std::int32_t>{ids[0], ids[8 * 3]}));
  EXPECT_NEAR(static_cast<double>(c.size()), 200.0, 20.0);
}

}  // namespace
}  // namespace truecut::offline
