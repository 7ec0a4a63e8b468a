#include "offline_geometry_util.hpp"
#include "truecut/offline/registration.hpp"
#include "truecut/offline/surfaces.hpp"

#include <gtest/gtest.h>

#include <random>

namespace truecut::offline {
namespace {

using test_geo::rigid;

// A block with no symmetry that would leave a motion undetermined by ICP:
// 40 × 30 × 20 mm, 8 quads per face edge.
TriangleMesh nominal_block() {
  return test_geo::box({-20, -15, -10}, {40, 30, 20}, 8);
}

// With σ = 0.03 mm scan noise on 30–50k scan points the registered pose
// scatters from seed to seed by about 0.004° and 0.001 mm (measured over 12
// seeds); the tolerances are 3–4 times that. Without noise ICP is exact to
// 1e-15.
constexpr double kAngleTolerance_deg = 0.015;
constexpr double kShiftTolerance_mm = 0.004;

// Rotation angle (deg) and translation distance (mm) between two transforms.
std::pair<double, double> difference(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  const Eigen::Isometry3d d = a * b.inverse();
  return {Eigen::AngleAxisd(d.linear()).angle() * 180.0 / M_PI, d.translation().norm()};
}

// The scan of a block as machined: the nominal moved by `misplaced` (where the
// scanner put it), sampled at 10 pt/mm² with σ = 0.03 mm noise.
std::vector<Eigen::Vector3d> scan_of(const TriangleMesh& part, const Eigen::Isometry3d& misplaced,
                                     std::uint32_t seed) {
  std::vector<Eigen::Vector3d> pts = test_geo::sample_surface(part, 10.0, 0.03, seed);
  transform_points(misplaced, pts);
  return pts;
}

TEST(Registration, RecoversRigidMisalignmentUnderNoise) {
  const TriangleMesh nominal = nominal_block();
  const Eigen::Isometry3d misplaced = rigid({1, 2, -1}, 0.8, {0.4, -0.25, 0.3});
  const std::vector<Eigen::Vector3d> scan = scan_of(nominal, misplaced, 1);
  const IcpResult r = register_scan(nominal, scan);
  EXPECT_TRUE(r.converged);
  EXPECT_EQ(r.determined_directions, 6);
  const auto [angle_deg, shift_mm] = difference(r.scan_to_nominal, misplaced.inverse());
  EXPECT_LT(shift_mm, kShiftTolerance_mm);
  EXPECT_LT(angle_deg, kAngleTolerance_deg);
  EXPECT_GT(r.rms_before_mm, 0.1);
  EXPECT_NEAR(r.rms_after_mm, 0.03, 0.005);  // the noise is what is left
  // The report is the inverse motion, in readable units.
  EXPECT_NEAR(r.transform.rotation_angle_deg, 0.8, kAngleTolerance_deg);
  EXPECT_NEAR((r.transform.matrix - r.scan_to_nominal.matrix()).norm(), 0.0, 1e-15);
}

// A scan already in place moves only by its noise: the registration finds
// a motion of about its standard error, which the significance test does
// not apply (a false alarm has probability 0.001; none in 10 seeds). A
// misplacement of 0.03° and 3 µm — five times the pose's scatter — is applied.
TEST(Registration, MotionWithinTheNoiseIsNotApplied) {
  const TriangleMesh nominal = nominal_block();
  for (std::uint32_t seed = 1; seed <= 10; ++seed) {
    const IcpResult r =
        register_scan(nominal, scan_of(nominal, Eigen::Isometry3d::Identity(), seed));
    EXPECT_FALSE(r.applied) << "seed " << seed << ": chi2 " << r.motion_chi2;
    EXPECT_LE(r.motion_chi2, r.motion_threshold) << seed;
    EXPECT_NEAR(r.motion_threshold, 22.46, 0.5);  // χ²(6) at 0.001 (Wilson–Hilferty)
    EXPECT_TRUE(r.scan_to_nominal.isApprox(Eigen::Isometry3d::Identity(), 0.0)) << seed;
    EXPECT_EQ(r.rms_after_mm, r.rms_before_mm) << seed;

    IcpOptions always;
    always.significance_level = 0.0;
    const IcpResult moved =
        register_scan(nominal, scan_of(nominal, Eigen::Isometry3d::Identity(), seed), always);
    EXPECT_TRUE(moved.applied);
    EXPECT_GT(moved.transform.rotation_angle_deg, 0.0);
  }
  const Eigen::Isometry3d misplaced = rigid({0.3, -0.5, 1}, 0.03, {0.002, 0.002, -0.001});
  const IcpResult r = register_scan(nominal, scan_of(nominal, misplaced, 3));
  EXPECT_TRUE(r.applied) << "chi2 " << r.motion_chi2;
  EXPECT_GT(r.motion_chi2, r.motion_threshold);
  const auto [angle_deg, shift_mm] = difference(r.scan_to_nominal, misplaced.inverse());
  EXPECT_LT(angle_deg, 0.01);
  EXPECT_LT(shift_mm, kShiftTolerance_mm);
}

TEST(Registration, IsDeterministic) {
  const TriangleMesh nominal = nominal_block();
  const std::vector<Eigen::Vector3d> scan = scan_of(nominal, rigid({0, 0, 1}, 0.5, {0.2, 0, 0}), 2);
  const IcpResult a = register_scan(nominal, scan);
  const IcpResult b = register_scan(nominal, scan);
  EXPECT_EQ(a.scan_to_nominal.matrix(), b.scan_to_nominal.matrix());
  EXPECT_EQ(a.iterations, b.iterations);
}

// Iterations after the first look the nearest scan point up among the
// previous iteration's nearest few while the pose moves less than their
// spacing: the same pairs as asking the k-d tree every time, so the same
// transform to the last bit.
TEST(Registration, ReusedNeighboursGiveTheTreesAnswer) {
  const TriangleMesh nominal = nominal_block();
  const std::vector<Eigen::Vector3d> scan =
      scan_of(nominal, rigid({1, -1, 2}, 0.6, {0.3, 0.1, -0.2}), 5);
  IcpOptions tree_every_time;
  tree_every_time.reuse_neighbours = false;
  const IcpResult reused = register_scan(nominal, scan);
  const IcpResult asked = register_scan(nominal, scan, tree_every_time);
  EXPECT_GT(reused.iterations, 3);
  EXPECT_EQ(reused.iterations, asked.iterations);
  EXPECT_EQ(reused.correspondences, asked.correspondences);
  EXPECT_EQ(reused.scan_to_nominal.matrix(), asked.scan_to_nominal.matrix());
  EXPECT_EQ(reused.rms_after_mm, asked.rms_after_mm);
}

TEST(Registration, TukeyIgnoresAFixtureThatBiasesPlainLeastSquares) {
  // The part stands on a fixture plate: its bottom face is hidden, and the
  // scanner sees the plate 0.5 mm below where the bottom face would be.
  const TriangleMesh nominal = nominal_block();
  TriangleMesh visible = nominal;
  visible.triangles.erase(visible.triangles.begin() + 4 * 128, visible.triangles.begin() + 5 * 128);
  std::vector<Eigen::Vector3d> scan = test_geo::sample_surface(visible, 10.0, 0.03, 3);
  const TriangleMesh fixture = test_geo::plate(50, 40, 1, 1, [](double, double) { return -10.5; });
  for (Eigen::Vector3d p : test_geo::sample_surface(fixture, 10.0, 0.03, 4))
    scan.push_back(p - Eigen::Vector3d(25, 20, 0));
  const Eigen::Isometry3d misplaced = rigid({0, 1, 0}, 0.3, {0.1, 0.2, -0.1});
  transform_points(misplaced, scan);

  const auto [ta, ts] =
      difference(register_scan(nominal, scan).scan_to_nominal, misplaced.inverse());
  EXPECT_LT(ts, kShiftTolerance_mm);
  EXPECT_LT(ta, kAngleTolerance_deg);
  IcpOptions plain;
  plain.kernel = RobustKernel::kNone;
  const auto [pa, ps] =
      difference(register_scan(nominal, scan, plain).scan_to_nominal, misplaced.inverse());
  EXPECT_GT(ps, 0.05);  // what the robust weighting saves
  (void)pa;
}

TEST(Registration, DatumRegionsKeepADeformedFaceOutOfTheFit) {
  // The part as machined: the top face bulges up by up to 0.3 mm.
  const TriangleMesh nominal = nominal_block();
  TriangleMesh machined = nominal;
  for (Eigen::Vector3d& p : machined.vertices_mm) {
    // Zero on the top face's border, so the side faces keep their shape.
    if (p.z() > 9.999)
      p.z() += 0.3 * (1 - (p.x() / 20) * (p.x() / 20)) * (1 - (p.y() / 15) * (p.y() / 15));
  }
  const Eigen::Isometry3d misplaced = rigid({1, 0, 0}, 0.4, {0.0, 0.3, 0.2});
  const std::vector<Eigen::Vector3d> scan = scan_of(machined, misplaced, 5);

  const std::vector<std::int32_t> ids = segment_surfaces(nominal);
  std::vector<std::int32_t> datums;
  for (int face = 0; face < 5; ++face)  // all but the top (+z, the sixth face)
    datums.push_back(ids[static_cast<std::size_t>(face) * 128]);
  IcpOptions restricted;
  restricted.datum_triangles = triangles_of_surfaces(ids, datums);
  restricted.kernel = RobustKernel::kNone;  // the datum choice alone must do it
  const auto [ra, rs] =
      difference(register_scan(nominal, scan, restricted).scan_to_nominal, misplaced.inverse());
  EXPECT_LT(rs, kShiftTolerance_mm);
  EXPECT_LT(ra, kAngleTolerance_deg);

  IcpOptions everything;
  everything.kernel = RobustKernel::kNone;
  const auto [ea, es] =
      difference(register_scan(nominal, scan, everything).scan_to_nominal, misplaced.inverse());
  EXPECT_GT(es, 0.02);  // the bulge pulls an unrestricted fit
  (void)ea;
}

TEST(Registration, PlaneLeavesInPlaneMotionUndetermined) {
  const TriangleMesh nominal = test_geo::plate(50, 50, 10, 10, [](double, double) { return 0.0; });
  std::vector<Eigen::Vector3d> scan = test_geo::sample_surface(nominal, 5.0, 0.0, 6);
  for (Eigen::Vector3d& p : scan)
    p.z() += 0.2;
  const IcpResult r = register_scan(nominal, scan);
  EXPECT_EQ(r.determined_directions, 3);  // z, tilt about x, tilt about y
  EXPECT_NEAR(r.scan_to_nominal.translation().z(), -0.2, 1e-9);
  EXPECT_NEAR(r.scan_to_nominal.translation().head<2>().norm(), 0.0, 1e-9);
}

// A closed cylinder (R 30, H 40) tessellated with 360 facets around: its
// facets constrain the turn about its axis only by their tilt within a facet
// (about 3e-5 of the best-determined direction here), which is no constraint
// on the machined part the scan shows. The turn must be left undetermined,
// not fitted to the facets; the other five directions are found.
TEST(Registration, FacetsOfASurfaceOfRevolutionDoNotDetermineItsTurn) {
  constexpr int kAround = 360;
  constexpr double kR = 30.0, kH = 40.0;
  TriangleMesh m;
  for (int row = 0; row <= 4; ++row)
    for (int i = 0; i < kAround; ++i) {
      const double t = 2.0 * M_PI * i / kAround;
      m.vertices_mm.emplace_back(kR * std::cos(t), kR * std::sin(t), kH * row / 4.0);
    }
  const auto bottom = static_cast<std::uint32_t>(m.vertices_mm.size());
  m.vertices_mm.emplace_back(0, 0, 0);
  m.vertices_mm.emplace_back(0, 0, kH);
  for (std::uint32_t row = 0; row < 4; ++row)
    for (std::uint32_t i = 0; i < kAround; ++i) {
      const std::uint32_t a = row * kAround + i, b = row * kAround + (i + 1) % kAround;
      m.triangles.push_back({a, b, b + kAround});
      m.triangles.push_back({a, b + kAround, a + kAround});
    }
  for (std::uint32_t i = 0; i < kAround; ++i) {
    m.triangles.push_back({bottom, (i + 1) % kAround, i});
    m.triangles.push_back({bottom + 1, 4 * kAround + i, 4 * kAround + (i + 1) % kAround});
  }
  // The part as machined: a true cylinder, scanned with σ 5 µm, 2 pt/mm²,
  // misplaced by a translation.
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.005);
  const Eigen::Vector3d shift(0.05, -0.03, 0.02);
  std::vector<Eigen::Vector3d> scan;
  for (int k = 0; k < 15000; ++k) {
    const double t = 2.0 * M_PI * u(rng);
    scan.push_back(Eigen::Vector3d((kR + noise(rng)) * std::cos(t), (kR + noise(rng)) * std::sin(t),
                                   kH * u(rng)) +
                   shift);
  }
  for (int k = 0; k < 6000; ++k) {
    const double r = kR * std::sqrt(u(rng)), t = 2.0 * M_PI * u(rng);
    scan.push_back(
        Eigen::Vector3d(r * std::cos(t), r * std::sin(t), (k % 2 ? kH : 0.0) + noise(rng)) + shift);
  }
  const IcpResult r = register_scan(m, scan);
  EXPECT_EQ(r.determined_directions, 5);
  EXPECT_TRUE(r.applied);
  EXPECT_NEAR((r.scan_to_nominal.translation() + shift).norm(), 0.0, 0.002);
  const Eigen::AngleAxisd turn(r.scan_to_nominal.linear());
  EXPECT_LT(std::abs(turn.angle() * turn.axis().z()), 1e-6) << "turn about the axis, rad";
}

TEST(Registration, DescribesTransformsInDegrees) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(3 * M_PI / 180, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(-2 * M_PI / 180, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(1 * M_PI / 180, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  T.translation() = Eigen::Vector3d(1, 2, 3);
  const RigidTransformReport r = describe_transform(T);
  EXPECT_NEAR((r.rotation_xyz_deg - Eigen::Vector3d(1, -2, 3)).norm(), 0.0, 1e-12);
  EXPECT_EQ(r.translation_mm, Eigen::Vector3d(1, 2, 3));
}

// Rigid-body motion removal.

struct Field {
  std::vector<Eigen::Vector3d> points, normals, displacements;
};

// Points on the block's faces with their normals.
Field block_points() {
  const TriangleMesh m = nominal_block();
  const std::vector<Eigen::Vector3d> fn = face_normals(m);
  Field f;
  for (std::size_t t = 0; t < m.triangles.size(); t += 3) {
    const auto& [a, b, c] = m.triangles[t];
    f.points.push_back((m.vertices_mm[a] + m.vertices_mm[b] + m.vertices_mm[c]) / 3.0);
    f.normals.push_back(fn[t]);
  }
  return f;
}

TEST(RigidBodyMotion, PureRigidMotionLeavesNothing) {
  Field f = block_points();
  const Eigen::Isometry3d T = rigid({1, -1, 2}, 0.2, {0.05, -0.02, 0.08});
  for (const Eigen::Vector3d& p : f.points)
    f.displacements.push_back(T * p - p);
  const RigidBodyMotion m =
      fit_rigid_body_motion(f.points, f.displacements, RigidBodyFit::kFullVectors);
  EXPECT_EQ(m.points_used, f.points.size());
  EXPECT_GT(m.rms_before_mm, 0.05);
  EXPECT_LT(m.rms_after_mm, 1e-12);
  // Translation = mean displacement (eq. 3–4).
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& v : f.displacements)
    mean += v;
  mean /= static_cast<double>(f.displacements.size());
  EXPECT_NEAR((m.translation_mm - mean).norm(), 0.0, 1e-15);
  EXPECT_NEAR((m.transform.matrix - T.matrix()).norm(), 0.0, 1e-12);
  remove_rigid_body_motion(m, RigidBodyFit::kFullVectors, f.points, f.displacements);
  for (const auto& v : f.displacements)
    EXPECT_LT(v.norm(), 1e-12);
}

TEST(RigidBodyMotion, NormalComponentsOnlyStillFindTheMotion) {
  Field f = block_points();
  const Eigen::Isometry3d T = rigid({2, 1, -1}, 0.3, {-0.04, 0.07, 0.02});
  // The ray method sees only the normal component of a displacement.
  for (std::size_t i = 0; i < f.points.size(); ++i) {
    const Eigen::Vector3d u = T * f.points[i] - f.points[i];
    f.displacements.push_back(u.dot(f.normals[i]) * f.normals[i]);
  }
  const RigidBodyMotion m = fit_rigid_body_motion(f.points, f.displacements,
                                                  RigidBodyFit::kNormalComponents, {}, f.normals);
  EXPECT_EQ(m.determined_directions, 6);
  EXPECT_NEAR((m.transform.matrix - T.matrix()).norm(), 0.0, 1e-10);
  remove_rigid_body_motion(m, RigidBodyFit::kNormalComponents, f.points, f.displacements,
                           f.normals);
  for (const auto& v : f.displacements)
    EXPECT_LT(v.norm(), 1e-10);
}

TEST(RigidBodyMotion, KeepsTheDeformationThatIsNotRigid) {
  // Rigid misalignment plus a bending line w(x) along z on the top face.
  Field f = block_points();
  const Eigen::Isometry3d T = rigid({0, 1, 0}, 0.1, {0.02, 0.0, -0.03});
  std::vector<Eigen::Vector3d> bend(f.points.size(), Eigen::Vector3d::Zero());
  for (std::size_t i = 0; i < f.points.size(); ++i) {
    const double x = (f.points[i].x() + 20) / 40;  // 0 … 1 along the block
    if (f.normals[i].z() > 0.5) bend[i].z() = 0.1 * x * x * (3 - x) / 2;
    f.displacements.push_back(T * f.points[i] - f.points[i] + bend[i]);
  }
  // Fitted on the faces that did not bend (the datum), removed everywhere.
  std::vector<std::uint8_t> use(f.points.size());
  for (std::size_t i = 0; i < use.size(); ++i)
    use[i] = f.normals[i].z() > 0.5 ? 0 : 1;
  const RigidBodyMotion m =
      fit_rigid_body_motion(f.points, f.displacements, RigidBodyFit::kFullVectors, use);
  EXPECT_LT(m.points_used, f.points.size());
  remove_rigid_body_motion(m, RigidBodyFit::kFullVectors, f.points, f.displacements);
  for (std::size_t i = 0; i < f.points.size(); ++i)
    EXPECT_NEAR((f.displacements[i] - bend[i]).norm(), 0.0, 1e-12) << i;
}

TEST(RigidBodyMotion, RejectsTooFewPoints) {
  const std::vector<Eigen::Vector3d> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const std::vector<Eigen::Vector3d> v(3, Eigen::Vector3d::Zero());
  const std::vector<std::uint8_t> use = {1, 1, 0};
  EXPECT_THROW(fit_rigid_body_motion(p, v, RigidBodyFit::kFullVectors, use), std::invalid_argument);
  EXPECT_THROW(fit_rigid_body_motion(p, v, RigidBodyFit::kNormalComponents), std::invalid_argument);
}

}  // namespace
}  // namespace truecut::offline
