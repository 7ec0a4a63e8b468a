// The two field-fit methods: the multilevel B-spline default and the
// regularised least-squares system kept selectable.
#include "truecut/offline/field_fit.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace truecut::offline {
namespace {

// Cantilever bending line along x (0.1 mm at x = 60) on the plane z = 5,
// 60 × 20 mm sampled every pitch_mm, optional noise along z.
std::vector<FitSample> bending_plane(double pitch_mm, double noise_mm = 0.0) {
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<FitSample> s;
  for (double y = 0.0; y <= 20.0 + 1e-9; y += pitch_mm)
    for (double x = 0.0; x <= 60.0 + 1e-9; x += pitch_mm) {
      FitSample p;
      p.position_mm = {x, y, 5.0};
      const double t = x / 60.0;
      p.vector_mm = {0.0, 0.0, 0.1 * t * t * (3.0 - t) / 2.0 + noise_mm * noise(rng)};
      s.push_back(p);
    }
  return s;
}

double bending_z(double x_mm) {
  const double t = x_mm / 60.0;
  return 0.1 * t * t * (3.0 - t) / 2.0;
}

TEST(FieldFitMethods, BothRecoverTheBendingLineAndAgree) {
  const std::vector<ToolSamples> tools{{1, bending_plane(1.0)}};
  FieldFitOptions o;
  o.spacing_mm = 2.5;
  const FieldFitResult mba = fit_correction_field(tools, o);
  o.method = FieldFitMethod::kLeastSquares;
  const FieldFitResult lsq = fit_correction_field(tools, o);
  EXPECT_LT(mba.layers[0].residual_max_mm, 1e-3);
  EXPECT_LT(lsq.layers[0].residual_max_mm, 1e-3);
  ASSERT_EQ(mba.field.grid().dims, lsq.field.grid().dims);
  double worst = 0.0;
  for (double x = 0.0; x <= 60.0; x += 1.7)
    for (double y = 0.0; y <= 20.0; y += 1.3) {
      const Eigen::Vector3d p(x, y, 5.2);
      const double a = mba.field.evaluate(1, p).correction_mm.z();
      const double b = lsq.field.evaluate(1, p).correction_mm.z();
      EXPECT_LT(std::abs(a - bending_z(x)), 1e-3) << x << " " << y;
      worst = std::max(worst, std::abs(a - b));
    }
  EXPECT_LT(worst, 1e-3);
  // Same weights: they depend on the samples only.
  const auto wa = mba.field.nodes(1), wb = lsq.field.nodes(1);
  for (std::size_t n = 0; n < wa.size(); ++n)
    ASSERT_EQ(wa[n].weight, wb[n].weight);
}

// More smoothness passes less of the scanner noise into the field.
TEST(FieldFitMethods, MultilevelSmoothnessDampsNoise) {
  const std::vector<ToolSamples> tools{{1, bending_plane(0.5, 0.05)}};
  FieldFitOptions o;
  o.spacing_mm = 2.0;
  auto field_error = [&](double smoothness) {
    o.smoothness = smoothness;
    const FieldFitResult r = fit_correction_field(tools, o);
    double e = 0.0;
    for (const FitSample& s : tools[0].samples) {
      const double d =
          r.field.evaluate(1, s.position_mm).correction_mm.z() - bending_z(s.position_mm.x());
      e += d * d;
    }
    return std::sqrt(e / static_cast<double>(tools[0].samples.size()));
  };
  const double none = field_error(0.0), strong = field_error(1.0);
  std::printf("multilevel fit, sigma 50 um: field-true RMS %.2f um at smoothness 0, %.2f um at 1\n",
              none * 1e3, strong * 1e3);
  EXPECT_LT(strong, 0.9 * none);
  EXPECT_LT(none, 0.3 * 0.05);
}

}  // namespace
}  // namespace truecut::offline
