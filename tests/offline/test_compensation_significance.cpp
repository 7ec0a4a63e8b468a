#include "offline_geometry_util.hpp"
#include "truecut/offline/compensation_points.hpp"
#include "truecut/offline/compensation_significance.hpp"
#include "truecut/offline/error_vectors.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

namespace truecut::offline {
namespace {

constexpr double kSigmaMm = 0.02;

// A scanner's mesh of the plate z = w(x) over [0, 20] × [0, 10] mm: points
// every 0.2 mm with N(0, σ) along z, each grid cell split along its shorter
// diagonal as the simulated scanner does (which joins points whose noise
// happens to agree, the trap for a noise estimate from mesh rings).
TriangleMesh noisy_scan(double step_mm, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, kSigmaMm);
  const int nx = 101, ny = 51;
  TriangleMesh m;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const double x = 0.2 * i, y = 0.2 * j;
      m.vertices_mm.emplace_back(x, y, (x > 10.0 ? step_mm : 0.0) + noise(rng));
    }
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(i + nx * j); };
  for (int j = 0; j + 1 < ny; ++j)
    for (int i = 0; i + 1 < nx; ++i) {
      const std::uint32_t a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      const auto& v = m.vertices_mm;
      if ((v[a] - v[c]).norm() <= (v[b] - v[d]).norm()) {
        m.triangles.push_back({a, b, c});
        m.triangles.push_back({a, c, d});
      } else {
        m.triangles.push_back({a, b, d});
        m.triangles.push_back({b, c, d});
      }
    }
  return m;
}

struct Case {
  TriangleMesh nominal;
  std::vector<std::int32_t> ids;
  CompensationPoints points;
};

// Nominal: the plate z = 0, surface 1 for x < 10, surface 2 beyond;
// compensation points every 0.1 mm (denser than the scan: neighbouring
// error vectors share scan points).
Case plate_case() {
  Case c;
  c.nominal = test_geo::plate(20, 10, 40, 20, [](double, double) { return 0.0; });
  for (const Triangle& t : c.nominal.triangles) {
    const double x = (c.nominal.vertices_mm[t[0]].x() + c.nominal.vertices_mm[t[1]].x() +
                      c.nominal.vertices_mm[t[2]].x()) /
                     3.0;
    c.ids.push_back(x < 10.0 ? 1 : 2);
  }
  c.points = sample_compensation_points(c.nominal, c.ids, 0.1);
  return c;
}

SignificanceResult test_scan(const Case& c, const TriangleMesh& scan) {
  RayMethodOptions ray;
  ray.edge_exclusion_mm = 0.3;
  const ErrorVectors e = error_vectors_by_rays(c.nominal, c.points, RayScene(scan), ray);
  return test_compensation_significance(c.points, e, scan, Eigen::Isometry3d::Identity());
}

// The noise comes out of the scan itself, the mean error's uncertainty is
// carried correctly through error vectors that share scan points (checked
// against the scatter over 20 scans), a surface cut right is left alone and
// a 10 µm step under 20 µm noise is found.
TEST(CompensationSignificance, NoiseUncertaintyAndDecision) {
  const Case c = plate_case();
  constexpr int kScans = 20;
  double sum_mean = 0.0, sum_mean2 = 0.0, sum_predicted = 0.0;
  for (int seed = 1; seed <= kScans; ++seed) {
    const SignificanceResult r = test_scan(c, noisy_scan(0.01, static_cast<std::uint32_t>(seed)));
    ASSERT_TRUE(r.tested);
    ASSERT_EQ(r.surfaces.size(), 2u);
    const SurfaceSignificance& right = r.surfaces[0];  // surface 1, cut right
    const SurfaceSignificance& off = r.surfaces[1];    // surface 2, 10 µm high
    EXPECT_NEAR(right.noise_mm, kSigmaMm, 0.15 * kSigmaMm) << seed;
    EXPECT_NEAR(off.noise_mm, kSigmaMm, 0.15 * kSigmaMm) << seed;
    EXPECT_FALSE(right.compensated) << seed << ": chi2 " << right.chi2 << " > " << right.threshold;
    EXPECT_TRUE(off.compensated) << seed;
    EXPECT_NEAR(off.mean_normal_mm, 0.01, 4 * off.mean_uncertainty_mm) << seed;
    EXPECT_GT(right.scan_points, 1000u);
    sum_mean += right.mean_normal_mm;
    sum_mean2 += right.mean_normal_mm * right.mean_normal_mm;
    sum_predicted += right.mean_uncertainty_mm;
  }
  const double scatter = std::sqrt(sum_mean2 / kScans - std::pow(sum_mean / kScans, 2));
  const double predicted = sum_predicted / kScans;
  std::printf(
      "mean error of the surface cut right: scatter over %d scans %.2f um, predicted %.2f um\n",
      kScans, 1000 * scatter, 1000 * predicted);
  // 20 scans estimate a standard deviation to about ±16 %.
  EXPECT_NEAR(scatter, predicted, 0.35 * predicted);
}

// A large face with a real but tiny error: 1.6 µm over 60 × 60 mm under
// 20 µm noise is significant (χ² above its 0.001 quantile over ~200
// patches), but each 4 mm patch measures it to about its own size, so a
// compensation would carry as much noise as it removes: not compensated.
TEST(CompensationSignificance, SignificantButNotWorthIt) {
  std::mt19937 rng(8);
  std::normal_distribution<double> noise(0.0, kSigmaMm);
  TriangleMesh scan = test_geo::plate(60, 60, 300, 300, [](double, double) { return 0.0016; });
  for (Eigen::Vector3d& v : scan.vertices_mm)
    v.z() += noise(rng);
  const TriangleMesh nominal = test_geo::plate(60, 60, 60, 60, [](double, double) { return 0.0; });
  const std::vector<std::int32_t> ids(nominal.triangles.size(), 1);
  const CompensationPoints points = sample_compensation_points(nominal, ids, 0.5);
  const ErrorVectors e = error_vectors_by_rays(nominal, points, RayScene(scan));
  const SignificanceResult r =
      test_compensation_significance(points, e, scan, Eigen::Isometry3d::Identity());
  ASSERT_EQ(r.surfaces.size(), 1u);
  const SurfaceSignificance& f = r.surfaces[0];
  const double alpha_limit = chi2_quantile_upper(1e-3, static_cast<double>(f.patches));
  std::printf("1.6 um on 60 x 60 mm: chi2 %.0f over %zu patches, 0.001 quantile %.0f, limit %.0f\n",
              f.chi2, f.patches, alpha_limit, f.threshold);
  EXPECT_GT(f.chi2, alpha_limit);                                // significant
  EXPECT_EQ(f.threshold, 2.0 * static_cast<double>(f.patches));  // the larger limit here
  EXPECT_FALSE(f.compensated);                                   // not worth it
  EXPECT_NEAR(f.mean_normal_mm, 0.0016, 3 * f.mean_uncertainty_mm);
}

TEST(CompensationSignificance, GivenNoiseAndNoTest) {
  const Case c = plate_case();
  const TriangleMesh scan = noisy_scan(0.0, 3);
  RayMethodOptions ray;
  ray.edge_exclusion_mm = 0.3;
  const ErrorVectors e = error_vectors_by_rays(c.nominal, c.points, RayScene(scan), ray);
  SignificanceOptions o;
  o.noise_mm = 0.001;  // a scanner claimed 20× better than it is: noise looks like error
  SignificanceResult r =
      test_compensation_significance(c.points, e, scan, Eigen::Isometry3d::Identity(), o);
  EXPECT_TRUE(r.surfaces[0].compensated);
  EXPECT_EQ(r.surfaces[0].noise_mm, 0.001);
  o = {};
  o.significance_level = 0.0;  // no test: everything compensated
  r = test_compensation_significance(c.points, e, scan, Eigen::Isometry3d::Identity(), o);
  EXPECT_FALSE(r.tested);
  EXPECT_TRUE(r.surfaces[0].compensated && r.surfaces[1].compensated);
  EXPECT_GT(r.surfaces[0].noise_mm, 0.0);  // still estimated and reported
  o.significance_level = 1.0;
  EXPECT_THROW(test_compensation_significance(c.points, e, scan, Eigen::Isometry3d::Identity(), o),
               std::invalid_argument);
}

TEST(CompensationSignificance, ChiSquareQuantile) {
  // Tables: χ²₁ 10.83, χ²₅ 20.52, χ²₂₀ 45.31 at 0.001; χ²₁₀ 18.31 at 0.05.
  EXPECT_NEAR(chi2_quantile_upper(0.001, 1), 10.83, 0.6);
  EXPECT_NEAR(chi2_quantile_upper(0.001, 5), 20.52, 0.3);
  EXPECT_NEAR(chi2_quantile_upper(0.001, 20), 45.31, 0.3);
  EXPECT_NEAR(chi2_quantile_upper(0.05, 10), 18.31, 0.1);
  EXPECT_THROW(chi2_quantile_upper(0.0, 3), std::invalid_argument);
}

}  // namespace
}  // namespace truecut::offline
