// Virtual optical scanner: noise statistics against the model at normal and
// oblique incidence, occlusion, density, registration error, determinism.
//
// Statistical tolerances: for n independent normal deviates the sample
// standard deviation has a relative standard error of 1/√(2(n − 1)); the
// tests allow 5 of those (a false failure about once in 3·10⁶ runs), and
// the mean 5·σ/√n.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <numbers>

#include "test_paths.hpp"
#include "test_scanner_meshes.hpp"
#include "truecut/offline/mesh_io.hpp"
#include "truecut/sim/measure/scanner.hpp"

using namespace truecut::sim::measure;
using truecut::offline::TriangleMesh;
using truecut::test::box_mesh;
using truecut::test::plane_mesh;

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

ScanPose top_pose(double distance_mm = 300) {
  ScanPose p;
  p.position_mm = {0, 0, distance_mm};
  p.view_dir = -Eigen::Vector3d::UnitZ();
  p.up = Eigen::Vector3d::UnitY();
  p.reference_distance_mm = distance_mm;
  return p;
}

ScannerOptions one_pose(double sigma_mm, double density) {
  ScannerOptions o;
  o.sigma0_mm = sigma_mm;
  o.density_pt_per_mm2 = density;
  o.poses = {top_pose()};
  return o;
}

struct Moments {
  double mean = 0, std = 0;
  std::size_t n = 0;
};

Moments moments(const std::vector<double>& v) {
  Moments m;
  m.n = v.size();
  for (double x : v)
    m.mean += x;
  m.mean /= static_cast<double>(m.n);
  for (double x : v)
    m.std += (x - m.mean) * (x - m.mean);
  m.std = std::sqrt(m.std / static_cast<double>(m.n - 1));
  return m;
}

void expect_std(const Moments& m, double expected, const char* what) {
  const double rel_se = 1.0 / std::sqrt(2.0 * static_cast<double>(m.n - 1));
  EXPECT_NEAR(m.std, expected, 5 * rel_se * expected) << what << " n=" << m.n;
  EXPECT_NEAR(m.mean, 0.0, 5 * expected / std::sqrt(static_cast<double>(m.n))) << what;
}

// Errors along each point's ray for a plane through the origin with normal n.
std::vector<double> along_ray_errors(const ScanResult& r, const Eigen::Vector3d& n) {
  std::vector<double> e;
  for (std::size_t i = 0; i < r.cloud.points_mm.size(); ++i)
    e.push_back(r.cloud.points_mm[i].dot(n) / r.ray_dirs[i].dot(n));
  return e;
}

}  // namespace

TEST(Scanner, NoiseAtNormalIncidenceIsSigma0) {
  struct Case {
    ScanMode mode;
    double sigma_mm;
  };
  for (const Case c : {Case{ScanMode::kFringe, 0.005}, Case{ScanMode::kFringe, 0.020},
                       Case{ScanMode::kFringe, 0.050}, Case{ScanMode::kLaser, 0.020}}) {
    ScannerOptions o = one_pose(c.sigma_mm, 25);
    o.mode = c.mode;
    const ScanResult r = scan(plane_mesh({0, 0, 0}, Eigen::Vector3d::UnitZ(), 20), o);
    ASSERT_GT(r.cloud.points_mm.size(), 30000u);
    std::vector<double> z;
    for (const auto& p : r.cloud.points_mm)
      z.push_back(p.z());
    expect_std(moments(z), c.sigma_mm, c.mode == ScanMode::kFringe ? "fringe" : "laser");
  }
}

TEST(Scanner, ObliqueIncidenceFollowsSigma0OverCosineAndTheCap) {
  // Plane tilted about Y towards the projector (which sits on +X).
  for (double tilt_deg : {60.0, 72.0}) {
    const Eigen::Vector3d n(std::sin(tilt_deg * kDeg), 0, std::cos(tilt_deg * kDeg));
    const ScannerOptions o = one_pose(0.010, 25);
    const ScanResult r = scan(plane_mesh({0, 0, 0}, n, 15), o);
    ASSERT_GT(r.cloud.points_mm.size(), 5000u) << tilt_deg;
    std::vector<double> standardised;
    double predicted_sum = 0;
    const std::vector<double> e = along_ray_errors(r, n);
    for (std::size_t i = 0; i < e.size(); ++i) {
      const double cos_in = -r.ray_dirs[i].dot(n);
      const double predicted = 0.010 * std::min(1.0 / cos_in, o.max_sigma_factor);
      predicted_sum += predicted;
      standardised.push_back(e[i] / predicted);
    }
    expect_std(moments(standardised), 1.0, "standardised");
    // The model's σ at this tilt: 2·σ0 at 60°, the cap 3·σ0 at 72° (1/cos = 3.24).
    const double expected = tilt_deg == 60.0 ? 0.020 : 0.030;
    EXPECT_NEAR(predicted_sum / static_cast<double>(e.size()), expected, 0.05 * expected);
    expect_std(moments(e), expected, "along the ray");
  }
}

TEST(Scanner, BeyondTheIncidenceLimitNothingIsMeasured) {
  const Eigen::Vector3d n(std::sin(80 * kDeg), 0, std::cos(80 * kDeg));
  const ScanResult r = scan(plane_mesh({0, 0, 0}, n, 15), one_pose(0.010, 25));
  EXPECT_EQ(0u, r.cloud.points_mm.size());
  EXPECT_GT(r.stats.rejected_incidence, 1000u);
}

TEST(Scanner, DensityMatchesTheSetting) {
  for (ScanMode mode : {ScanMode::kFringe, ScanMode::kLaser}) {
    for (double density : {4.0, 25.0, 60.0}) {
      ScannerOptions o = one_pose(0.005, density);
      o.mode = mode;
      const ScanResult r = scan(plane_mesh({0, 0, 0}, Eigen::Vector3d::UnitZ(), 20), o);
      std::size_t inside = 0;
      for (const auto& p : r.cloud.points_mm)
        inside += std::abs(p.x()) < 10 && std::abs(p.y()) < 10;
      const double measured = static_cast<double>(inside) / 400.0;
      EXPECT_NEAR(measured, density, 0.10 * density) << density;
    }
  }
}

TEST(Scanner, SlotBottomInTheProjectorsShadowGetsNoPoints) {
  // A U-block: a slot 2 mm wide, 10 mm deep along Y.
  TriangleMesh u = box_mesh({-10, -10, 0}, {10, 10, 5});
  truecut::test::append_mesh(u, box_mesh({-10, -10, 5}, {-1, 10, 15}));
  truecut::test::append_mesh(u, box_mesh({1, -10, 5}, {10, 10, 15}));
  auto slot_bottom = [](const ScanResult& r) {
    std::size_t n = 0;
    for (const auto& p : r.cloud.points_mm)
      n += std::abs(p.x()) < 0.9 && std::abs(p.z() - 5) < 0.5;
    return n;
  };
  // Projector across the slot (right = +X): the walls shade the bottom.
  const ScanResult across = scan(u, one_pose(0.005, 25));
  EXPECT_EQ(0u, slot_bottom(across));
  EXPECT_GT(across.stats.occluded, 500u);
  // Projector along the slot: the same bottom is measured.
  ScannerOptions along = one_pose(0.005, 25);
  along.poses[0].up = Eigen::Vector3d::UnitX();
  EXPECT_GT(slot_bottom(scan(u, along)), 500u);
  // Laser line: the camera rides beside the laser along the sweep (up).
  ScannerOptions laser = one_pose(0.005, 25);
  laser.mode = ScanMode::kLaser;
  laser.poses[0].up = Eigen::Vector3d::UnitX();  // sweep and camera across the slot
  EXPECT_EQ(0u, slot_bottom(scan(u, laser)));
  laser.poses[0].up = Eigen::Vector3d::UnitY();  // along it
  EXPECT_GT(slot_bottom(scan(u, laser)), 500u);
}

TEST(Scanner, DefaultPosesSeeEveryFaceButTheUnderside) {
  ScannerOptions o;
  o.sigma0_mm = 0.005;
  o.density_pt_per_mm2 = 4;
  const ScanResult r = scan(box_mesh({-10, -8, 0}, {10, 8, 12}), o);
  ASSERT_EQ(5u, r.poses.size());
  std::size_t faces[6] = {};
  for (const auto& p : r.cloud.points_mm) {
    if (std::abs(p.x() + 10) < 0.05) ++faces[0];
    if (std::abs(p.x() - 10) < 0.05) ++faces[1];
    if (std::abs(p.y() + 8) < 0.05) ++faces[2];
    if (std::abs(p.y() - 8) < 0.05) ++faces[3];
    if (std::abs(p.z()) < 0.05) ++faces[4];
    if (std::abs(p.z() - 12) < 0.05) ++faces[5];
  }
  EXPECT_EQ(0u, faces[4]) << "underside";
  for (int f : {0, 1, 2, 3, 5})
    EXPECT_GT(faces[f], 100u) << "face " << f;
  // Each face is seen by its pose at normal incidence: about 4 pt/mm².
  EXPECT_NEAR(static_cast<double>(faces[5]) / 320.0, 4.0, 0.4);
}

TEST(Scanner, RegistrationErrorMovesTheCloudByTheTransform) {
  const TriangleMesh box = box_mesh({-10, -8, 0}, {10, 8, 12});
  ScannerOptions o;
  o.density_pt_per_mm2 = 2;
  const ScanResult plain = scan(box, o);
  const Eigen::Isometry3d t = seeded_registration_error(0.1, 0.2, {0, 0, 6}, 7);
  // The seeded transform has the requested size.
  EXPECT_NEAR(0.1, (t * Eigen::Vector3d(0, 0, 6) - Eigen::Vector3d(0, 0, 6)).norm(), 1e-12);
  EXPECT_NEAR(0.2 * kDeg, Eigen::AngleAxisd(t.linear()).angle(), 1e-12);
  o.registration_error = t;
  const ScanResult moved = scan(box, o);
  ASSERT_EQ(plain.cloud.points_mm.size(), moved.cloud.points_mm.size());
  for (std::size_t i = 0; i < plain.cloud.points_mm.size(); ++i) {
    ASSERT_LT((t * plain.cloud.points_mm[i] - moved.cloud.points_mm[i]).norm(), 1e-12);
    ASSERT_LT((t.linear() * plain.cloud.normals[i] - moved.cloud.normals[i]).norm(), 1e-12);
  }
}

TEST(Scanner, SameSeedSameBytesOtherSeedOtherNoise) {
  const TriangleMesh box = box_mesh({-10, -8, 0}, {10, 8, 12});
  ScannerOptions o;
  o.density_pt_per_mm2 = 4;
  o.build_mesh = true;
  const ScanResult a = scan(box, o), b = scan(box, o);
  ASSERT_EQ(a.cloud.points_mm.size(), b.cloud.points_mm.size());
  EXPECT_EQ(0, std::memcmp(a.cloud.points_mm.data(), b.cloud.points_mm.data(),
                           a.cloud.points_mm.size() * sizeof(Eigen::Vector3d)));
  EXPECT_EQ(0, std::memcmp(a.cloud.normals.data(), b.cloud.normals.data(),
                           a.cloud.normals.size() * sizeof(Eigen::Vector3d)));
  EXPECT_EQ(a.mesh.triangles, b.mesh.triangles);
  const auto dir = truecut::test::scratch_dir();
  truecut::offline::write_point_cloud(dir / "a.ply", a.cloud);
  truecut::offline::write_point_cloud(dir / "b.ply", b.cloud);
  EXPECT_EQ(truecut::test::read_file(dir / "a.ply"), truecut::test::read_file(dir / "b.ply"));
  o.seed = 2;
  const ScanResult c = scan(box, o);
  ASSERT_EQ(a.cloud.points_mm.size(), c.cloud.points_mm.size());
  std::size_t differ = 0;
  for (std::size_t i = 0; i < a.cloud.points_mm.size(); ++i)
    differ += a.cloud.points_mm[i] != c.cloud.points_mm[i];
  EXPECT_EQ(a.cloud.points_mm.size(), differ);
}

TEST(Scanner, EstimatedNormalsAndScanMeshFollowTheSurface) {
  const Eigen::Vector3d n(std::sin(30 * kDeg), 0, std::cos(30 * kDeg));
  ScannerOptions o = one_pose(0.020, 25);
  o.build_mesh = true;
  const ScanResult r = scan(plane_mesh({0, 0, 0}, n, 10), o);
  ASSERT_GT(r.cloud.points_mm.size(), 1000u);
  double worst_deg = 0, sum_deg = 0;
  for (const auto& m : r.cloud.normals) {
    const double a = std::acos(std::min(1.0, m.dot(n))) / kDeg;
    worst_deg = std::max(worst_deg, a);
    sum_deg += a;
  }
  EXPECT_LT(sum_deg / static_cast<double>(r.cloud.normals.size()), 2.0);
  EXPECT_LT(worst_deg, 10.0);
  // Grid triangulation: about two triangles per point, all facing the scanner.
  EXPECT_EQ(r.mesh.vertices_mm.size(), r.cloud.points_mm.size());
  EXPECT_GT(r.mesh.triangles.size(), 19 * r.cloud.points_mm.size() / 10);
  for (const auto& t : r.mesh.triangles) {
    const auto& v = r.mesh.vertices_mm;
    ASSERT_GT((v[t[1]] - v[t[0]]).cross(v[t[2]] - v[t[0]]).dot(n), 0);
  }
}

TEST(Scanner, ScanMeshDoesNotBridgeASlot) {
  TriangleMesh u = box_mesh({-10, -10, 0}, {10, 10, 5});
  truecut::test::append_mesh(u, box_mesh({-10, -10, 5}, {-1, 10, 15}));
  truecut::test::append_mesh(u, box_mesh({1, -10, 5}, {10, 10, 15}));
  ScannerOptions o = one_pose(0.005, 25);
  o.build_mesh = true;
  const ScanResult r = scan(u, o);
  ASSERT_GT(r.mesh.triangles.size(), 1000u);
  for (const auto& t : r.mesh.triangles)
    for (int k = 0; k < 3; ++k)
      ASSERT_LT((r.mesh.vertices_mm[t[k]] - r.mesh.vertices_mm[t[(k + 1) % 3]]).norm(), 1.0);
}

TEST(Scanner, OutOfRangeSettingsAreRefused) {
  const TriangleMesh box = box_mesh({0, 0, 0}, {1, 1, 1});
  for (double sigma : {0.0049, 0.0501}) {
    ScannerOptions o;
    o.sigma0_mm = sigma;
    EXPECT_THROW(scan(box, o), std::invalid_argument) << sigma;
  }
  ScannerOptions o;
  o.density_pt_per_mm2 = 0;
  EXPECT_THROW(scan(box, o), std::invalid_argument);
  o = {};
  o.max_rays_per_pose = 20;  // a 1 mm box at 25 pt/mm² needs about 64
  EXPECT_THROW(scan(box, o), std::invalid_argument);
  o = {};
  o.poses = {top_pose(0.5)};  // camera inside the box's height
  EXPECT_THROW(scan(box, o), std::invalid_argument);
  EXPECT_THROW(scan(TriangleMesh{}, ScannerOptions{}), std::invalid_argument);
  EXPECT_THROW(seeded_registration_error(11, 0, {0, 0, 0}, 1), std::invalid_argument);
}
