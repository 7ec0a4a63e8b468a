// The sphere method on the cases of the model-adaptation source's own test
// design: a vertex on a surface, on an edge and on a corner of a part whose
// measured surface is displaced by 0.05–1 mm, scanned at 5–40 pt/mm² with
// σ = 0.03 mm noise.
#include "offline_geometry_util.hpp"
#include "test_names.hpp"
#include "truecut/offline/error_vectors.hpp"

#include <gtest/gtest.h>

#include <tbb/global_control.h>

#include <cmath>
#include <random>

namespace truecut::offline {
namespace {

constexpr double kSigma = 0.03;
constexpr double kRs = 2.0;
const Eigen::Vector3d kLo(0, 0, 0), kSize(20, 20, 20);

TriangleMesh nominal() {
  return test_geo::box(kLo, kSize, 10);
}

struct Case {
  SphereCase kind;
  std::vector<Eigen::Vector3d> at;  // nominal vertices of this kind
  std::vector<Eigen::Vector3d> edge_direction;
  double plane_fraction;  // of the sphere's cross-section each plane holds
  // RMS error in units of σ/√n (n: points per plane). A surface plane's
  // offset scatters by σ/√n. On an edge (corner) each plane is extrapolated
  // from its centroid, 4Rs/3π from the edge line (√2 times that from the
  // corner), with tilt errors ~σ/(√n·0.27Rs); two (three) such planes
  // intersect to give ≈ 2.7 (4.3) σ/√n.
  double rms_factor;
};

// Vertices of each kind, at least Rs + 1 mm from any other feature.
std::vector<Case> cases() {
  Case surface{SphereCase::kSurface, {}, {}, 1.0, 1.0};
  Case edge{SphereCase::kEdge, {}, {}, 0.5, 2.7};
  Case corner{SphereCase::kCorner, {}, {}, 0.25, 4.3};
  for (double x : {6.0, 10.0, 14.0})
    for (double y : {6.0, 10.0, 14.0})
      surface.at.emplace_back(x, y, 20.0);
  for (double t : {6.0, 10.0, 14.0}) {
    edge.at.emplace_back(20.0, t, 20.0);
    edge.edge_direction.emplace_back(0, 1, 0);
    edge.at.emplace_back(t, 0.0, 0.0);
    edge.edge_direction.emplace_back(1, 0, 0);
  }
  for (double x : {0.0, 20.0})
    for (double y : {0.0, 20.0})
      for (double z : {0.0, 20.0})
        corner.at.emplace_back(x, y, z);
  return {surface, edge, corner};
}

// What the method should find: a plane sees only the normal component of a
// displacement d, an edge all but the component along the edge, a corner d.
Eigen::Vector3d expected(const Case& c, std::size_t i, const Eigen::Vector3d& d) {
  switch (c.kind) {
    case SphereCase::kSurface:
      return Eigen::Vector3d(0, 0, d.z());
    case SphereCase::kEdge: {
      const Eigen::Vector3d& e = c.edge_direction[i];
      return d - d.dot(e) * e;
    }
    default:
      return d;
  }
}

class SphereMethod : public ::testing::TestWithParam<std::tuple<double, double>> {};

TEST_P(SphereMethod, SurfaceEdgeAndCornerDisplacementsAreRecovered) {
  const auto [displacement_mm, density] = GetParam();
  const Eigen::Vector3d d = displacement_mm * Eigen::Vector3d(1, -2, 3).normalized();
  TriangleMesh machined = nominal();
  for (Eigen::Vector3d& p : machined.vertices_mm)
    p += d;
  const auto seed = static_cast<std::uint32_t>(1000 * displacement_mm + density);
  const std::vector<Eigen::Vector3d> cloud =
      test_geo::sample_surface(machined, density, kSigma, seed);
  SphereMethodOptions o;
  o.radius_mm = kRs;
  std::size_t low_density_invalid = 0;
  for (const Case& c : cases()) {
    CompensationPoints pts;
    pts.positions_mm = c.at;
    pts.normals.assign(c.at.size(), Eigen::Vector3d::UnitZ());
    pts.surface_ids.assign(c.at.size(), 0);
    pts.triangles.assign(c.at.size(), 0);
    const ErrorVectors e = error_vectors_by_spheres(nominal(), pts, cloud, o);
    // Each plane holds ~density·π·Rs²·fraction points; the bound is 4× the
    // expected RMS error.
    // (Of the points the fits used: a dense scan is thinned, see
    // SphereMethodThinning.)
    const double n_plane = density * M_PI * kRs * kRs * c.plane_fraction * e.scan_fraction;
    const double tolerance = 4.0 * c.rms_factor * kSigma / std::sqrt(n_plane);
    for (std::size_t i = 0; i < c.at.size(); ++i) {
      // Below the source's 20 pt/mm² a corner displaced far keeps only a few
      // points on a face; the method must then say so, not guess.
      if (c.kind == SphereCase::kCorner && density < kRecommendedDensityPerMm2 && !e.valid(i)) {
        EXPECT_TRUE(e.status[i] == ErrorStatus::kTooFewPoints ||
                    e.status[i] == ErrorStatus::kPlaneTilted)
            << to_string(e.status[i]);
        ++low_density_invalid;
        continue;
      }
      ASSERT_EQ(e.status[i], ErrorStatus::kValid)
          << to_string(c.kind) << " at " << c.at[i].transpose() << ": " << to_string(e.status[i]);
      EXPECT_EQ(e.sphere_case[i], c.kind);
      EXPECT_LT((e.vectors_mm[i] - expected(c, i, d)).norm(), tolerance)
          << to_string(c.kind) << " at " << c.at[i].transpose() << " found "
          << e.vectors_mm[i].transpose() << " expected " << expected(c, i, d).transpose();
    }
  }
  if (displacement_mm < 1.0) {
    EXPECT_EQ(low_density_invalid, 0u);
  }
}

INSTANTIATE_TEST_SUITE_P(DisplacementAndDensity, SphereMethod,
                         ::testing::Combine(::testing::Values(0.05, 0.2, 1.0),
                                            ::testing::Values(5.0, 20.0, 40.0)),
                         // e.g. "Displacement0p05mm_Density20PerMm2"
                         [](const ::testing::TestParamInfo<std::tuple<double, double>>& info) {
                           return "Displacement" +
                                  truecut::test::test_name(std::get<0>(info.param)) + "mm_Density" +
                                  truecut::test::test_name(std::get<1>(info.param)) + "PerMm2";
                         });

CompensationPoints one_point(const Eigen::Vector3d& p) {
  CompensationPoints c;
  c.positions_mm = {p};
  c.normals = {Eigen::Vector3d::UnitZ()};
  c.surface_ids = {0};
  c.triangles = {0};
  return c;
}

TEST(SphereMethodLimits, FewerThanFivePointsIsInvalid) {
  const std::vector<Eigen::Vector3d> cloud = {
      {10, 10, 20}, {10.5, 10, 20}, {10, 10.5, 20}, {9.5, 10, 20}, {20, 20, 20}};
  SphereMethodOptions o;
  o.radius_mm = kRs;
  const ErrorVectors e = error_vectors_by_spheres(nominal(), one_point({10, 10, 20}), cloud, o);
  EXPECT_EQ(e.status[0], ErrorStatus::kTooFewPoints);
  EXPECT_EQ(e.points_in_sphere[0], 4u);
  // A fifth point makes it valid.
  std::vector<Eigen::Vector3d> more = cloud;
  more.emplace_back(10, 9.5, 20);
  EXPECT_EQ(error_vectors_by_spheres(nominal(), one_point({10, 10, 20}), more, o).status[0],
            ErrorStatus::kValid);
}

TEST(SphereMethodLimits, DisplacementBeyondSevenTenthsOfTheRadiusIsInvalid) {
  SphereMethodOptions o;
  o.radius_mm = 1.5;  // reach 1.05 mm
  for (double lift : {1.0, 1.2}) {
    TriangleMesh machined = nominal();
    for (Eigen::Vector3d& p : machined.vertices_mm)
      p.z() += lift;
    const auto cloud = test_geo::sample_surface(machined, 40.0, 0.0, 9);
    const ErrorVectors e = error_vectors_by_spheres(nominal(), one_point({10, 10, 20}), cloud, o);
    if (lift < 1.05) {
      ASSERT_EQ(e.status[0], ErrorStatus::kValid);
      EXPECT_NEAR(e.normal_mm[0], lift, 1e-9);
    } else {
      EXPECT_EQ(e.status[0], ErrorStatus::kBeyondSphereReach);
    }
  }
}

// The source's plane fit keeps the nominal orientation and fits only the
// offset: the mean distance of the points along the normal. A tilted scan
// plane seen on one side of the point tells the two apart: the tilted fit
// evaluates the plane at the point, the parallel one gives the points' mean.
TEST(SphereMethodLimits, ParallelPlanesFitTheMeanOffsetTiltedPlanesThePlane) {
  const double slope = 0.02, lift = 0.05;
  std::vector<Eigen::Vector3d> cloud;
  double sum = 0.0;
  for (int i = 0; i <= 15; ++i)
    for (int j = -10; j <= 10; ++j) {
      const double x = 10.0 + 0.1 * i, y = 10.0 + 0.1 * j;
      cloud.emplace_back(x, y, 20.0 + lift + slope * (x - 10.0));
      sum += lift + slope * (x - 10.0);
    }
  const double mean_offset = sum / static_cast<double>(cloud.size());
  SphereMethodOptions o;
  o.radius_mm = kRs;
  o.max_points_per_sphere = 0;  // all 336 points: the exact mean below
  const ErrorVectors tilted =
      error_vectors_by_spheres(nominal(), one_point({10, 10, 20}), cloud, o);
  o.tilted_planes = false;
  const ErrorVectors parallel =
      error_vectors_by_spheres(nominal(), one_point({10, 10, 20}), cloud, o);
  ASSERT_EQ(tilted.status[0], ErrorStatus::kValid);
  ASSERT_EQ(parallel.status[0], ErrorStatus::kValid);
  EXPECT_NEAR(parallel.normal_mm[0], mean_offset, 1e-9);
  // The tilted plane's displacement of the point is perpendicular to that
  // plane; its component along the nominal normal is lift · cos² θ.
  EXPECT_NEAR(tilted.normal_mm[0], lift / (1.0 + slope * slope), 1e-9);
  EXPECT_GT(mean_offset - lift, 0.01);  // the two differ by the slope's lever
}

TEST(SphereMethodLimits, DensityIsReported) {
  const auto cloud = test_geo::sample_surface(nominal(), 12.0, kSigma, 10);
  SphereMethodOptions o;
  o.radius_mm = kRs;
  CompensationPoints pts;
  for (double x : {6.0, 8.0, 10.0, 12.0, 14.0}) {
    pts.positions_mm.emplace_back(x, 10, 20);
    pts.normals.push_back(Eigen::Vector3d::UnitZ());
    pts.surface_ids.push_back(0);
    pts.triangles.push_back(0);
  }
  const ErrorVectors e = error_vectors_by_spheres(nominal(), pts, cloud, o);
  const ErrorVectorSummary s = summarize(e, o.radius_mm);
  EXPECT_NEAR(s.median_density_per_mm2, 12.0, 12.0 * 0.25);  // Poisson scatter of ~150 points
  EXPECT_EQ(s.below_recommended_density, 5u);                // 12 < 20 pt/mm²
  EXPECT_EQ(s.by_case[static_cast<int>(SphereCase::kSurface)], 5u);
}

// A patch of the top face (z = 20) lifted by `lift_mm`, `density` points per
// mm² uniformly at random with σ = kSigma along z.
std::vector<Eigen::Vector3d> dense_patch(double density, double lift_mm, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(4.0, 16.0);
  std::normal_distribution<double> noise(0.0, kSigma);
  std::vector<Eigen::Vector3d> cloud(static_cast<std::size_t>(density * 12.0 * 12.0));
  for (Eigen::Vector3d& p : cloud) {
    const double x = u(rng), y = u(rng);
    p = {x, y, 20.0 + lift_mm + noise(rng)};
  }
  return cloud;
}

CompensationPoints patch_points() {
  CompensationPoints pts;
  for (double x : {8.0, 10.0, 12.0})
    for (double y : {8.0, 10.0, 12.0}) {
      pts.positions_mm.emplace_back(x, y, 20);
      pts.normals.push_back(Eigen::Vector3d::UnitZ());
      pts.surface_ids.push_back(0);
      pts.triangles.push_back(0);
    }
  return pts;
}

// A scan so dense that each sphere holds ~2,500 points: with the default
// bound the fits use a fixed subset of about 256 per sphere, keep their
// accuracy for that many points, report the scan's true density, and name
// the scan's own points as their support.
TEST(SphereMethodThinning, DenseScanIsFittedOnASubsetOfAboutTheBound) {
  constexpr double kDensity = 200.0, kLift = 0.05;
  const std::vector<Eigen::Vector3d> cloud = dense_patch(kDensity, kLift, 21);
  const CompensationPoints pts = patch_points();
  SphereMethodOptions o;
  o.radius_mm = kRs;
  ASSERT_EQ(o.max_points_per_sphere, 256u);
  const ErrorVectors e = error_vectors_by_spheres(nominal(), pts, cloud, o);
  const double per_sphere = kDensity * M_PI * kRs * kRs;  // 2,513
  EXPECT_NEAR(e.scan_fraction, 256.0 / per_sphere, 0.1 * 256.0 / per_sphere);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    ASSERT_EQ(e.status[i], ErrorStatus::kValid) << to_string(e.status[i]);
    // Poisson scatter of ~256 points: 4 standard deviations.
    EXPECT_NEAR(e.points_in_sphere[i], 256.0, 4.0 * 16.0);
    EXPECT_NEAR(e.normal_mm[i], kLift, 4.0 * kSigma / std::sqrt(e.points_in_sphere[i]));
    ASSERT_EQ(e.support_begin[i + 1] - e.support_begin[i], e.points_in_sphere[i]);
    for (std::uint32_t k = e.support_begin[i]; k < e.support_begin[i + 1]; ++k) {
      ASSERT_LT(e.support_point[k], cloud.size());
      EXPECT_LE((cloud[e.support_point[k]] - pts.positions_mm[i]).norm(), kRs);
    }
  }
  const ErrorVectorSummary s = summarize(e, o.radius_mm);
  EXPECT_NEAR(s.median_density_per_mm2, kDensity, 0.1 * kDensity);

  o.max_points_per_sphere = 0;  // every point, as the source
  const ErrorVectors all = error_vectors_by_spheres(nominal(), pts, cloud, o);
  EXPECT_EQ(all.scan_fraction, 1.0);
  EXPECT_NEAR(all.points_in_sphere[4], per_sphere, 4.0 * std::sqrt(per_sphere));
  EXPECT_NEAR(all.normal_mm[4], kLift, 4.0 * kSigma / std::sqrt(all.points_in_sphere[4]));
}

TEST(SphereMethodThinning, TheSubsetDoesNotDependOnTheThreadCount) {
  const std::vector<Eigen::Vector3d> cloud = dense_patch(200.0, 0.05, 22);
  const CompensationPoints pts = patch_points();
  SphereMethodOptions o;
  o.radius_mm = kRs;
  ErrorVectors one;
  {
    const tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    one = error_vectors_by_spheres(nominal(), pts, cloud, o);
  }
  const ErrorVectors any = error_vectors_by_spheres(nominal(), pts, cloud, o);
  ASSERT_LT(one.scan_fraction, 1.0);
  EXPECT_EQ(one.vectors_mm, any.vectors_mm);
  EXPECT_EQ(one.support_point, any.support_point);
  EXPECT_EQ(one.support_weight, any.support_weight);
}

// Below the bounds nothing changes: the same result, bit for bit, as with
// every point and every facet.
TEST(SphereMethodThinning, ScanAndFacetsBelowTheBoundsAreUsedWhole) {
  const std::vector<Eigen::Vector3d> cloud = dense_patch(15.0, 0.05, 23);  // ~190 per sphere
  const CompensationPoints pts = patch_points();
  SphereMethodOptions o;
  o.radius_mm = kRs;
  const ErrorVectors bounded = error_vectors_by_spheres(nominal(), pts, cloud, o);
  o.max_points_per_sphere = 0;
  o.max_facets_per_sphere = 0;
  const ErrorVectors all = error_vectors_by_spheres(nominal(), pts, cloud, o);
  EXPECT_EQ(bounded.scan_fraction, 1.0);
  EXPECT_EQ(bounded.nominal_fraction, 1.0);
  EXPECT_EQ(bounded.vectors_mm, all.vectors_mm);
  EXPECT_EQ(bounded.support_point, all.support_point);
}

// A 4 mm box of 0.1 mm facets (about 630 per sphere of 1 mm) standing on a
// floor of two facets: the facets beside the point are thinned to about 64
// per sphere, and the planes are the same as from every facet, a face's
// included where only a sliver of it reaches into the sphere (of the top's
// fine facets, a sliver holds one or two: without the facets along the
// edges kept, some are lost).
TEST(SphereMethodFacetThinning, FineFacetsBesideCoarseOnesGiveTheSameVectorsAsEveryFacet) {
  constexpr int kK = 40;
  TriangleMesh box = test_geo::box(Eigen::Vector3d::Zero(), Eigen::Vector3d(4, 4, 4), kK);
  std::vector<Triangle> kept;
  for (const Triangle& t : box.triangles) {
    if (box.vertices_mm[t[0]].z() != 0.0 || box.vertices_mm[t[1]].z() != 0.0 ||
        box.vertices_mm[t[2]].z() != 0.0)
      kept.push_back(t);
  }
  auto corner = [&](double x, double y) {
    for (std::uint32_t v = 0; v < box.vertices_mm.size(); ++v)
      if (box.vertices_mm[v] == Eigen::Vector3d(x, y, 0.0)) return v;
    ADD_FAILURE() << "no corner " << x << " " << y;
    return 0u;
  };
  const std::uint32_t c00 = corner(0, 0), c10 = corner(4, 0), c11 = corner(4, 4),
                      c01 = corner(0, 4);
  kept.push_back({c00, c11, c10});  // facing -z
  kept.push_back({c00, c01, c11});
  box.triangles = kept;

  const Eigen::Vector3d d = 0.02 * Eigen::Vector3d(1, -2, 3).normalized();
  TriangleMesh machined = box;
  for (Eigen::Vector3d& p : machined.vertices_mm)
    p += d;
  const std::vector<Eigen::Vector3d> cloud = test_geo::sample_surface(machined, 100.0, 0.005, 31);

  CompensationPoints pts;
  auto add = [&](Eigen::Vector3d p, Eigen::Vector3d n) {
    pts.positions_mm.push_back(p);
    pts.normals.push_back(n.normalized());
    pts.surface_ids.push_back(0);
    pts.triangles.push_back(0);
  };
  const Eigen::Vector3d x(1, 0, 0), z(0, 0, 1);
  add({4, 2, 2}, x);            // the wall
  add({4, 2, 0.3}, x);          // the wall, the floor 0.3 mm away
  add({4, 2, 0.9}, x);          // the wall, a sliver of the floor in the sphere
  add({4, 2, 0}, x - z);        // the wall's edge on the floor
  add({3.6, 2, 0}, -z);         // the floor beside the wall
  add({4, 4, 0}, x - z);        // a corner on the floor
  add({4, 4, 4}, x + z);        // a corner of fine facets
  add({4, 2, 4}, x + z);        // an edge of fine facets
  for (int k = 0; k < 12; ++k)  // the wall, slivers of the fine top in the sphere
    add({4, 0.5 + 0.25 * k, 3.02 + 0.01 * k}, x);
  SphereMethodOptions o;
  o.radius_mm = 1.0;
  ASSERT_EQ(o.max_facets_per_sphere, 64u);
  const ErrorVectors thinned = error_vectors_by_spheres(box, pts, cloud, o);
  o.max_facets_per_sphere = 0;  // every facet, as the source
  const ErrorVectors all = error_vectors_by_spheres(box, pts, cloud, o);
  EXPECT_LT(thinned.nominal_fraction, 0.5);
  EXPECT_EQ(all.nominal_fraction, 1.0);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    SCOPED_TRACE(i);
    ASSERT_EQ(thinned.status[i], all.status[i]) << to_string(thinned.status[i]);
    EXPECT_EQ(thinned.status[i], ErrorStatus::kValid) << to_string(thinned.status[i]);
    EXPECT_EQ(thinned.sphere_case[i], all.sphere_case[i]);
    EXPECT_LE((thinned.vectors_mm[i] - all.vectors_mm[i]).norm(), 1e-9);
  }
  // And the planted displacement on the wall, where a plane sees its
  // normal component (σ / √256 of noise, 4 standard deviations).
  EXPECT_NEAR(thinned.normal_mm[0], d.x(), 4.0 * 0.005 / 16.0);
  EXPECT_NEAR(thinned.normal_mm[2], d.x(), 4.0 * 0.005 / 16.0);
}

}  // namespace
}  // namespace truecut::offline
