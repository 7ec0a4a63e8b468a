#include "truecut/offline/truss_smoothing.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>

#include <random>

namespace truecut::offline {
namespace {

// A flat n × n vertex grid (pitch_mm apart) in z = 0, each quad split along
// the same diagonal.
TriangleMesh plate(int n, double pitch_mm) {
  TriangleMesh m;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i)
      m.vertices_mm.emplace_back(i * pitch_mm, j * pitch_mm, 0.0);
  }
  auto id = [n](int i, int j) { return static_cast<std::uint32_t>(i + n * j); };
  for (int j = 0; j + 1 < n; ++j) {
    for (int i = 0; i + 1 < n; ++i) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  }
  return m;
}

std::vector<std::uint8_t> all_valid(const TriangleMesh& m) {
  return std::vector<std::uint8_t>(m.vertices_mm.size(), 1);
}

double rms_difference(const std::vector<Eigen::Vector3d>& a,
                      const std::vector<Eigen::Vector3d>& b) {
  double sum = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i)
    sum += (a[i] - b[i]).squaredNorm();
  return std::sqrt(sum / static_cast<double>(a.size()));
}

TEST(TrussSmoothing, EdgesAreUniqueAndSorted) {
  const std::vector<Triangle> tris{{0, 1, 2}, {2, 1, 3}};
  const auto edges = truss_bars(tris);
  ASSERT_EQ(edges.size(), 5u);
  EXPECT_EQ(edges[0], (std::array<std::uint32_t, 2>{0, 1}));
  EXPECT_EQ(edges[4], (std::array<std::uint32_t, 2>{2, 3}));
}

TEST(TrussSmoothing, ConstantFieldPassesUnchanged) {
  const TriangleMesh m = plate(21, 1.0);
  const std::vector<Eigen::Vector3d> v(m.vertices_mm.size(), Eigen::Vector3d(0.05, -0.02, 0.11));
  std::vector<std::uint8_t> valid = all_valid(m);
  for (std::size_t i = 0; i < valid.size(); i += 7)
    valid[i] = 0;
  for (TrussEdgeWeight w : {TrussEdgeWeight::kUniform, TrussEdgeWeight::kInverseLength}) {
    const TrussResult r = smooth_truss(m.vertices_mm, m.triangles, v, valid, {5.0, w});
    EXPECT_EQ(r.unsupported_count, 0);
    for (std::size_t i = 0; i < v.size(); ++i) {
      ASSERT_LT((r.displacement_mm[i] - v[i]).norm(), 1e-12) << "vertex " << i;
    }
  }
}

// Interior vertices of the regular triangulation reproduce a linear field
// exactly; at the border the bars pull inwards by about kb/kc · |∇v| · pitch.
TEST(TrussSmoothing, LinearFieldWithinTolerance) {
  constexpr int n = 41;
  const TriangleMesh m = plate(n, 1.0);
  const Eigen::Vector3d gradient(0.004, -0.002, 0.005);  // mm per mm along x
  std::vector<Eigen::Vector3d> v;
  for (const auto& p : m.vertices_mm)
    v.push_back(gradient * p.x() + Eigen::Vector3d(0, 0, 0.003 * p.y()));
  // The source's kb/kc: the border effect grows with it (about kb/kc · |∇v| ·
  // pitch; 10 µm at the default 1).
  TrussOptions source;
  source.kb_over_kc = 0.2;
  const TrussResult r = smooth_truss({}, m.triangles, v, all_valid(m), source);
  double interior_max = 0.0, border_max = 0.0;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const double e = (r.displacement_mm[i + n * j] - v[i + n * j]).norm();
      const bool interior = i >= 6 && j >= 6 && i < n - 6 && j < n - 6;
      (interior ? interior_max : border_max) = std::max(interior ? interior_max : border_max, e);
    }
  }
  EXPECT_LT(interior_max, 1e-4);  // 0.1 µm
  EXPECT_LT(border_max, 3e-3);    // 3 µm on a 0.2 mm ramp
  EXPECT_GT(border_max, 1e-5);    // the border effect exists: the check above is not vacuous
}

// An invalid hole inside the valid region is filled by the truss: a linear
// field is harmonic, so the fill is exact up to the border effect.
TEST(TrussSmoothing, InvalidHoleIsInterpolated) {
  constexpr int n = 31;
  const TriangleMesh m = plate(n, 1.0);
  std::vector<Eigen::Vector3d> v;
  std::vector<std::uint8_t> valid = all_valid(m);
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const double z = 0.002 * i + 0.001 * j;
      const bool hole = std::abs(i - 15) <= 4 && std::abs(j - 15) <= 4;
      valid[i + n * j] = hole ? 0 : 1;
      v.emplace_back(0.0, 0.0, hole ? std::nan("") : z);
    }
  }
  const TrussResult r = smooth_truss({}, m.triangles, v, valid);
  const double centre = r.displacement_mm[15 + n * 15].z();
  EXPECT_NEAR(centre, 0.002 * 15 + 0.001 * 15, 1e-5);
}

// |(kb/kc·K + C) d − C v|, max over vertices and components: the
// equilibrium the solver must satisfy, whichever way it solves it.
double equilibrium_error(const TriangleMesh& m, const std::vector<Eigen::Vector3d>& v,
                         const std::vector<std::uint8_t>& valid, double kb_over_kc,
                         const TrussResult& r) {
  std::vector<Eigen::Vector3d> force(v.size(), Eigen::Vector3d::Zero());
  for (const auto& [a, b] : truss_bars(m.triangles)) {
    const Eigen::Vector3d f = kb_over_kc * (r.displacement_mm[a] - r.displacement_mm[b]);
    force[a] += f;
    force[b] -= f;
  }
  double worst = 0.0;
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (valid[i]) force[i] += r.displacement_mm[i] - v[i];
    worst = std::max(worst, force[i].cwiseAbs().maxCoeff());
  }
  return worst;
}

// The solver takes conjugate gradients where they converge fast (most
// vertices valid) and a sparse factorisation where they would not (a stiff
// truss, a large invalid region): either way the equilibrium holds.
TEST(TrussSmoothing, SolvesTheEquilibriumWhateverTheConditioning) {
  constexpr int n = 61;
  const TriangleMesh m = plate(n, 1.0);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 0.03);
  std::vector<Eigen::Vector3d> v;
  for (int k = 0; k < n * n; ++k)
    v.emplace_back(noise(rng), noise(rng), 0.1 + noise(rng));
  std::vector<std::uint8_t> valid = all_valid(m), sparse = all_valid(m);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      sparse[i + n * j] = (i % 20 == 0 && j % 20 == 0) ? 1 : 0;  // 16 valid of 3721
  for (const double kb_over_kc : {0.2, 1e4}) {
    for (const auto* mask : {&valid, &sparse}) {
      TrussOptions o;
      o.kb_over_kc = kb_over_kc;
      const TrussResult r = smooth_truss({}, m.triangles, v, *mask, o);
      EXPECT_LT(equilibrium_error(m, v, *mask, kb_over_kc, r), 1e-10)
          << "kb/kc " << kb_over_kc << (mask == &sparse ? ", 16 valid vertices" : ", all valid");
    }
  }
}

TEST(TrussSmoothing, ComponentWithoutValidVertexIsZeroAndReported) {
  TriangleMesh a = plate(5, 1.0);
  const TriangleMesh b = plate(4, 1.0);
  const auto offset = static_cast<std::uint32_t>(a.vertices_mm.size());
  for (const auto& p : b.vertices_mm)
    a.vertices_mm.push_back(p + Eigen::Vector3d(10, 0, 0));
  for (const auto& t : b.triangles)
    a.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  a.vertices_mm.emplace_back(50, 0, 0);  // isolated, invalid vertex

  std::vector<Eigen::Vector3d> v(a.vertices_mm.size(), Eigen::Vector3d(0, 0, 0.07));
  std::vector<std::uint8_t> valid(a.vertices_mm.size(), 1);
  for (std::size_t i = offset; i < valid.size(); ++i)
    valid[i] = 0;
  const TrussResult r = smooth_truss({}, a.triangles, v, valid);
  EXPECT_EQ(r.unsupported_count, 16 + 1);
  for (std::size_t i = 0; i < offset; ++i) {
    EXPECT_EQ(r.supported[i], 1);
    EXPECT_NEAR(r.displacement_mm[i].z(), 0.07, 1e-12);
  }
  for (std::size_t i = offset; i < v.size(); ++i) {
    EXPECT_EQ(r.supported[i], 0);
    EXPECT_EQ(r.displacement_mm[i], Eigen::Vector3d::Zero());
  }
}

// Smooth bending-like displacement along the normal plus Gaussian noise along
// the normal, as a scanner transfers it.
struct NoisyCase {
  std::vector<Eigen::Vector3d> truth, measured;
};
NoisyCase noisy_plate(const TriangleMesh& m, double sigma_mm, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma_mm);
  NoisyCase c;
  for (const auto& p : m.vertices_mm) {
    const double x = p.x() / 60.0, y = p.y() / 60.0;
    const Eigen::Vector3d t(0.0, 0.0, 0.08 * x * x * (3.0 - x) / 2.0 + 0.02 * std::sin(3.0 * y));
    c.truth.push_back(t);
    c.measured.push_back(t + Eigen::Vector3d(0, 0, noise(rng)));
  }
  return c;
}

TEST(TrussSmoothing, ReducesNoiseTransferAtDefaults) {
  const TriangleMesh m = plate(61, 1.0);
  for (double sigma_mm : {0.020, 0.050}) {
    const NoisyCase c = noisy_plate(m, sigma_mm, 20261121);
    const TrussResult r = smooth_truss({}, m.triangles, c.measured, all_valid(m));
    const double raw = rms_difference(c.measured, c.truth);
    const double smoothed = rms_difference(r.displacement_mm, c.truth);
    std::printf(
        "truss kb/kc=1 sigma=%.0f um: raw-true RMS %.2f um, smoothed-true RMS %.2f um (x%.2f)\n",
        sigma_mm * 1e3, raw * 1e3, smoothed * 1e3, smoothed / raw);
    EXPECT_LT(smoothed, 0.4 * raw) << "sigma " << sigma_mm;
  }
}

TEST(TrussSmoothing, StifferTrussSmoothsMore) {
  const TriangleMesh m = plate(41, 1.0);
  const NoisyCase c = noisy_plate(m, 0.02, 7);
  double previous = 1e9;
  for (double ratio : {0.0, 0.2, 1.0, 5.0}) {
    const TrussResult r = smooth_truss({}, m.triangles, c.measured, all_valid(m), {ratio});
    const double e = rms_difference(r.displacement_mm, c.truth);
    EXPECT_LT(e, previous) << "kb/kc " << ratio;
    previous = e;
  }
}

// The axial-bar truss (the source's) against its definition as a least-
// squares problem, written independently of the stiffness assembly: minimise
// Σ_bars kb/kc · (e_ab · (d_b − d_a))² + Σ_valid |d_i − v_i|², rows stacked
// and solved by a dense QR. A bent, irregular patch so every bar has its own
// direction.
TEST(TrussSmoothingAxialBars, MatchesTheEnergyMinimumOfAxialBars) {
  TriangleMesh m = plate(5, 1.3);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  for (auto& p : m.vertices_mm)
    p += Eigen::Vector3d(jitter(rng), jitter(rng), 0.2 * p.x() * p.x() + jitter(rng));
  std::normal_distribution<double> noise(0.0, 0.02);
  std::vector<Eigen::Vector3d> v;
  for (std::size_t i = 0; i < m.vertices_mm.size(); ++i)
    v.emplace_back(noise(rng), noise(rng), noise(rng));
  const std::vector<std::uint8_t> valid = all_valid(m);
  const double ratio = 0.7;
  TrussOptions o{ratio};
  o.stiffness = TrussStiffness::kAxialBars;
  const TrussResult r = smooth_truss(m.vertices_mm, m.triangles, v, valid, o);

  const auto bars = truss_bars(m.triangles);
  const auto n = static_cast<Eigen::Index>(v.size());
  Eigen::MatrixXd rows =
      Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(bars.size()) + 3 * n, 3 * n);
  Eigen::VectorXd target = Eigen::VectorXd::Zero(rows.rows());
  Eigen::Index row = 0;
  for (const auto& b : bars) {
    const Eigen::Vector3d e = (m.vertices_mm[b[1]] - m.vertices_mm[b[0]]).normalized();
    rows.block<1, 3>(row, 3 * b[1]) = std::sqrt(ratio) * e.transpose();
    rows.block<1, 3>(row, 3 * b[0]) = -std::sqrt(ratio) * e.transpose();
    ++row;
  }
  for (Eigen::Index i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) {
      rows(row, 3 * i + c) = 1.0;
      target(row++) = v[static_cast<std::size_t>(i)](c);
    }
  }
  const Eigen::VectorXd reference = rows.colPivHouseholderQr().solve(target);
  for (Eigen::Index i = 0; i < n; ++i)
    EXPECT_LT((r.displacement_mm[static_cast<std::size_t>(i)] - reference.segment<3>(3 * i)).norm(),
              1e-12)
        << "vertex " << i;
}

// A small rigid rotation strains no bar: it passes unchanged, the border
// included (zero-length springs pull the border of a linear field inward).
TEST(TrussSmoothingAxialBars, ASmallRigidRotationPassesUnchanged) {
  const TriangleMesh m = plate(15, 1.0);
  const Eigen::Vector3d omega(2e-4, -1e-4, 3e-4);  // rad
  std::vector<Eigen::Vector3d> v;
  for (const auto& p : m.vertices_mm)
    v.push_back(omega.cross(p) + Eigen::Vector3d(0.01, 0.02, -0.03));
  TrussOptions o{5.0};
  o.stiffness = TrussStiffness::kAxialBars;
  const TrussResult axial = smooth_truss(m.vertices_mm, m.triangles, v, all_valid(m), o);
  const TrussResult springs = smooth_truss(m.vertices_mm, m.triangles, v, all_valid(m), {5.0});
  EXPECT_LT(rms_difference(axial.displacement_mm, v), 1e-12);
  EXPECT_GT(rms_difference(springs.displacement_mm, v), 1e-4);
}

// On a flat face every bar lies in the face: a displacement along the normal
// strains none of them, so normal noise is not smoothed at all, while the
// zero-length springs remove most of it. In-plane noise is smoothed.
TEST(TrussSmoothingAxialBars, OnAFlatFaceTheNormalComponentIsNotSmoothed) {
  const TriangleMesh m = plate(41, 1.0);
  const NoisyCase c = noisy_plate(m, 0.02, 5);
  TrussOptions o{1.0};
  o.stiffness = TrussStiffness::kAxialBars;
  const TrussResult axial = smooth_truss(m.vertices_mm, m.triangles, c.measured, all_valid(m), o);
  EXPECT_LT(rms_difference(axial.displacement_mm, c.measured), 1e-12);

  std::mt19937 rng(9);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::vector<Eigen::Vector3d> in_plane;
  for (std::size_t i = 0; i < m.vertices_mm.size(); ++i)
    in_plane.emplace_back(noise(rng), noise(rng), 0.0);
  const std::vector<Eigen::Vector3d> zero(in_plane.size(), Eigen::Vector3d::Zero());
  const TrussResult smoothed = smooth_truss(m.vertices_mm, m.triangles, in_plane, all_valid(m), o);
  EXPECT_LT(rms_difference(smoothed.displacement_mm, zero), 0.8 * rms_difference(in_plane, zero));
}

// An invalid vertex on a flat face: its in-plane displacement comes from the
// bars, its normal one (a mechanism) is 0; an isolated invalid component is
// unsupported and 0.
TEST(TrussSmoothingAxialBars, InvalidVerticesFollowTheBarsOnlyWhereBarsHoldThem) {
  const TriangleMesh m = plate(9, 1.0);
  const std::vector<Eigen::Vector3d> v(m.vertices_mm.size(), Eigen::Vector3d(0.01, -0.02, 0.03));
  std::vector<std::uint8_t> valid = all_valid(m);
  const std::size_t centre = 4 + 9 * 4;
  valid[centre] = 0;
  TrussOptions o{1.0};
  o.stiffness = TrussStiffness::kAxialBars;
  const TrussResult r = smooth_truss(m.vertices_mm, m.triangles, v, valid, o);
  EXPECT_EQ(0, r.unsupported_count);
  EXPECT_NEAR(0.01, r.displacement_mm[centre].x(), 1e-9);
  EXPECT_NEAR(-0.02, r.displacement_mm[centre].y(), 1e-9);
  EXPECT_NEAR(0.0, r.displacement_mm[centre].z(), 1e-9);
  EXPECT_THROW(smooth_truss({}, m.triangles, v, valid, o), std::invalid_argument);
}

TEST(TrussSmoothing, RejectsBadInput) {
  const TriangleMesh m = plate(3, 1.0);
  const std::vector<Eigen::Vector3d> v(m.vertices_mm.size(), Eigen::Vector3d::Zero());
  std::vector<std::uint8_t> valid = all_valid(m);
  EXPECT_THROW(smooth_truss({}, m.triangles, v, std::span(valid).first(3)), std::invalid_argument);
  EXPECT_THROW(smooth_truss({}, m.triangles, v, valid, {-1.0}), std::invalid_argument);
  EXPECT_THROW(smooth_truss({}, m.triangles, v, valid, {0.2, TrussEdgeWeight::kInverseLength}),
               std::invalid_argument);
  std::vector<Triangle> bad = m.triangles;
  bad[1][2] = 99;
  EXPECT_THROW(smooth_truss({}, bad, v, valid), std::invalid_argument);
  std::vector<Eigen::Vector3d> nan = v;
  nan[4].x() = std::nan("");
  EXPECT_THROW(smooth_truss({}, m.triangles, nan, valid), std::invalid_argument);
  valid[4] = 0;
  EXPECT_NO_THROW(smooth_truss({}, m.triangles, nan, valid));
}

}  // namespace
}  // namespace truecut::offline
