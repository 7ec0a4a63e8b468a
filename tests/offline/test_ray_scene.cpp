#include "offline_geometry_util.hpp"
#include "truecut/offline/mesh_geometry.hpp"
#include "truecut/offline/ray_scene.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>
#include <string>

namespace truecut::offline {
namespace {

TEST(RayScene, HitFarFromTheOriginIsExactInDouble) {
  // One triangle 10 m from the workpiece origin: float32 there resolves only
  // ~1 µm, the local origin and the double refinement keep the hit exact.
  const Eigen::Vector3d o(10000.0, -7000.0, 3000.0);
  TriangleMesh m;
  m.vertices_mm = {o, o + Eigen::Vector3d(10, 0, 0), o + Eigen::Vector3d(0, 10, 0.5)};
  m.triangles = {{0, 1, 2}};
  const RayScene scene(m);
  const Eigen::Vector3d target = o + 0.2 * (m.vertices_mm[1] - o) + 0.3 * (m.vertices_mm[2] - o);
  const Eigen::Vector3d dir = Eigen::Vector3d(0.1, -0.2, -1.0).normalized();
  const Ray ray{target - 1.2345678 * dir, dir, 0.0, 10.0};
  RayHit hit;
  scene.intersect({&ray, 1}, {&hit, 1});
  ASSERT_TRUE(hit.hit());
  EXPECT_EQ(hit.triangle, 0u);
  EXPECT_NEAR(hit.distance_mm, 1.2345678, 1e-9);
  EXPECT_NEAR(hit.u, 0.2, 1e-9);
  EXPECT_NEAR(hit.v, 0.3, 1e-9);
  const Eigen::Vector3d n = (m.vertices_mm[1] - o).cross(m.vertices_mm[2] - o).normalized();
  EXPECT_NEAR((hit.normal - n).norm(), 0.0, 1e-12);

  // Embree's own float result: same triangle, same normal orientation, the
  // distance only to float precision.
  RayHit raw;
  scene.intersect({&ray, 1}, {&raw, 1}, {RayBatch::kSingle, false});
  ASSERT_TRUE(raw.hit());
  EXPECT_GT(raw.normal.dot(n), 0.999);
  EXPECT_NEAR(raw.distance_mm, 1.2345678, 1e-4);
}

TEST(RayScene, SearchIntervalAndMissesAreHonoured) {
  const TriangleMesh m = test_geo::plate(10, 10, 4, 4, [](double, double) { return 0.0; });
  const RayScene scene(m);
  const std::vector<Ray> rays = {
      {{5, 5, 1}, {0, 0, -1}, 0.0, 0.99},  // stops short of the plate
      {{5, 5, 1}, {0, 0, -1}, 1.01, 5.0},  // starts past it
      {{15, 5, 1}, {0, 0, -1}, 0.0, 5.0},  // beside it
      {{5, 5, 1}, {0, 0, 1}, 0.0, 5.0},    // away from it
      {{5, 5, 1}, {0, 0, -1}, 0.0, 1.01},  // hits
  };
  std::vector<RayHit> hits(rays.size());
  scene.intersect(rays, hits);
  for (int i = 0; i < 4; ++i)
    EXPECT_FALSE(hits[i].hit()) << i;
  ASSERT_TRUE(hits[4].hit());
  EXPECT_NEAR(hits[4].distance_mm, 1.0, 1e-12);
  // A +z facing plate seen from above: normal opposes the ray.
  EXPECT_NEAR(hits[4].normal.z(), 1.0, 1e-12);
}

TEST(RayScene, AllBatchModesGiveIdenticalHits) {
  const TriangleMesh m = test_geo::plate(40, 30, 80, 60, [](double x, double y) {
    return 0.5 * std::sin(0.2 * x) * std::cos(0.3 * y);
  });
  const RayScene scene(m);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> xy(-2.0, 42.0), tilt(-0.3, 0.3);
  std::vector<Ray> rays(1003);  // not a multiple of 16
  for (Ray& r : rays) {
    r.origin_mm = {xy(rng), 0.75 * xy(rng), 2.0};
    r.direction = Eigen::Vector3d(tilt(rng), tilt(rng), -1.0).normalized();
    r.t_max_mm = 10.0;
  }
  std::vector<RayHit> single(rays.size()), packet(rays.size()), stream(rays.size());
  scene.intersect(rays, single, {RayBatch::kSingle, true});
  scene.intersect(rays, packet, {RayBatch::kPacket16, true});
  scene.intersect(rays, stream, {RayBatch::kStream, true});
  std::size_t hit_count = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    hit_count += single[i].hit();
    for (const auto* other : {&packet[i], &stream[i]}) {
      ASSERT_EQ(single[i].triangle, other->triangle) << i;
      EXPECT_EQ(single[i].distance_mm, other->distance_mm) << i;
      EXPECT_EQ(single[i].u, other->u) << i;
      EXPECT_EQ(single[i].normal, other->normal) << i;
    }
  }
  EXPECT_GT(hit_count, 800u);
  EXPECT_LT(hit_count, rays.size());
}

TEST(RayScene, TrianglesWithinMatchesBruteForce) {
  const TriangleMesh m = test_geo::box({-5, -4, -3}, {10, 8, 6}, 6);
  const RayScene scene(m);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> c(-6.0, 6.0);
  for (int q = 0; q < 50; ++q) {
    const Eigen::Vector3d p(c(rng), c(rng), c(rng));
    const double r = 0.3 + 0.05 * q;
    std::vector<std::uint32_t> got;
    scene.triangles_within(p, r, got);
    std::vector<std::uint32_t> want;
    for (std::size_t t = 0; t < m.triangles.size(); ++t) {
      const auto& [a, b, d] = m.triangles[t];
      const Eigen::Vector3d x =
          closest_point_on_triangle(p, m.vertices_mm[a], m.vertices_mm[b], m.vertices_mm[d]);
      if ((x - p).norm() <= r) want.push_back(static_cast<std::uint32_t>(t));
    }
    EXPECT_EQ(got, want) << "query " << q;
    // With closest points: the same triangles, each with its closest point.
    std::vector<RayScene::NearTriangle> with_points;
    scene.triangles_within(p, r, with_points);
    ASSERT_EQ(with_points.size(), want.size()) << "query " << q;
    for (std::size_t i = 0; i < want.size(); ++i) {
      EXPECT_EQ(with_points[i].triangle, want[i]);
      const auto& [a, b, d] = m.triangles[want[i]];
      EXPECT_EQ(with_points[i].closest_mm,
                closest_point_on_triangle(p, m.vertices_mm[a], m.vertices_mm[b], m.vertices_mm[d]));
    }
  }
}

// A scan registered by placing its scene (set_world_from_mesh) answers as a
// scene built from the moved vertices: same triangles, distances and
// normals, to rounding.
TEST(RayScene, PlacedSceneAnswersAsAMovedMesh) {
  const TriangleMesh m = test_geo::plate(40, 30, 80, 60, [](double x, double y) {
    return 0.5 * std::sin(0.2 * x) * std::cos(0.3 * y);
  });
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  pose.translation() = Eigen::Vector3d(120.0, -35.0, 8.0);
  TriangleMesh moved = m;
  for (Eigen::Vector3d& v : moved.vertices_mm)
    v = pose * v;
  RayScene placed(m);
  placed.set_world_from_mesh(pose);
  const RayScene reference(moved);

  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> xy(-2.0, 42.0), tilt(-0.3, 0.3);
  std::vector<Ray> rays(500);
  for (Ray& r : rays) {
    r.origin_mm = pose * Eigen::Vector3d(xy(rng), 0.75 * xy(rng), 2.0);
    r.direction = pose.linear() * Eigen::Vector3d(tilt(rng), tilt(rng), -1.0).normalized();
    r.t_max_mm = 10.0;
  }
  std::vector<RayHit> a(rays.size()), b(rays.size());
  placed.intersect(rays, a);
  reference.intersect(rays, b);
  std::size_t hits = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    ASSERT_EQ(a[i].triangle, b[i].triangle) << i;
    if (!a[i].hit()) continue;
    ++hits;
    EXPECT_NEAR(a[i].distance_mm, b[i].distance_mm, 1e-9) << i;
    EXPECT_NEAR((a[i].normal - b[i].normal).norm(), 0.0, 1e-12) << i;
  }
  EXPECT_GT(hits, 400u);

  const Eigen::Vector3d p = pose * Eigen::Vector3d(20.0, 15.0, 0.3);
  std::vector<std::uint32_t> near_a, near_b;
  placed.triangles_within(p, 1.5, near_a);
  reference.triangles_within(p, 1.5, near_b);
  EXPECT_FALSE(near_a.empty());
  EXPECT_EQ(near_a, near_b);
  std::vector<RayScene::NearTriangle> points_a, points_b;
  placed.triangles_within(p, 1.5, points_a);
  reference.triangles_within(p, 1.5, points_b);
  ASSERT_EQ(points_a.size(), near_a.size());
  ASSERT_EQ(points_b.size(), near_b.size());
  for (std::size_t i = 0; i < points_a.size(); ++i) {
    EXPECT_EQ(points_a[i].triangle, points_b[i].triangle);
    EXPECT_NEAR((points_a[i].closest_mm - points_b[i].closest_mm).norm(), 0.0, 1e-9) << i;
  }

  placed.set_world_from_mesh(Eigen::Isometry3d::Identity());  // back where it was built
  RayHit h;
  const Ray down{{20.0, 15.0, 3.0}, {0, 0, -1}, 0.0, 10.0};
  placed.intersect({&down, 1}, {&h, 1});
  ASSERT_TRUE(h.hit());
  EXPECT_NEAR(h.distance_mm, 3.0 - 0.5 * std::sin(4.0) * std::cos(4.5), 2e-3);
}

TEST(RayScene, RejectsIndexOutOfRange) {
  TriangleMesh m;
  m.vertices_mm = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.triangles = {{0, 1, 3}};
  try {
    RayScene scene(m);
    FAIL() << "no exception";
  } catch (const RayEngineError& e) {
    EXPECT_NE(std::string(e.what()).find("triangle 0 refers to vertex 3"), std::string::npos)
        << e.what();
  }
}

// Issue 23 (sweep F1): a CMM point at x = 1e20 mm reached Embree, which
// asserted and ended the process (SIGABRT). Such rays and query points are
// refused with an exception, in every batch mode; a far but real ray works.
TEST(RayScene, RaysAndPointsEmbreeCannotTakeAreRefused) {
  const TriangleMesh m = test_geo::plate(10, 10, 4, 4, [](double, double) { return 0.0; });
  const RayScene scene(m);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<Ray> bad = {
      {{1e20, 0, 5}, {1, 0, 0}, 0.0, 1.0},
      {{nan, 0, 5}, {0, 0, -1}, 0.0, 1.0},
      {{5, 5, 1}, {0, 0, 0}, 0.0, 1.0},
      {{5, 5, 1}, {0, 0, -1}, nan, 1.0},
  };
  for (const RayBatch batch : {RayBatch::kSingle, RayBatch::kPacket16, RayBatch::kStream})
    for (std::size_t k = 0; k < bad.size(); ++k) {
      std::vector<Ray> rays = {{{5, 5, 1}, {0, 0, -1}, 0.0, 5.0}, bad[k]};
      std::vector<RayHit> hits(rays.size());
      try {
        scene.intersect(rays, hits, {batch, true});
        ADD_FAILURE() << "ray " << k << " was cast";
      } catch (const RayEngineError& e) {
        EXPECT_NE(std::string(e.what()).find("ray 2 of 2: origin"), std::string::npos) << e.what();
      }
    }
  std::vector<std::uint32_t> near;
  EXPECT_THROW(scene.triangles_within({1e20, 0, 0}, 1.0, near), RayEngineError);
  EXPECT_THROW(scene.triangles_within({0, nan, 0}, 1.0, near), RayEngineError);
  const std::vector<Ray> far = {{{5, 5, 1e8}, {0, 0, -1}, 0.0, 2e8}};
  std::vector<RayHit> hit(1);
  scene.intersect(far, hit);
  ASSERT_TRUE(hit[0].hit());
  EXPECT_NEAR(hit[0].distance_mm, 1e8, 1e-6);
}

}  // namespace
}  // namespace truecut::offline
