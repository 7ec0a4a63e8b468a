#include "offline_geometry_util.hpp"
#include "truecut/offline/error_vectors.hpp"
#include "truecut/offline/registration.hpp"
#include "truecut/offline/surfaces.hpp"

#include <gtest/gtest.h>

namespace truecut::offline {
namespace {

using test_geo::box;
using test_geo::plate;

TriangleMesh moved(TriangleMesh m, const Eigen::Vector3d& by) {
  for (Eigen::Vector3d& p : m.vertices_mm)
    p += by;
  return m;
}

// Hand-placed compensation points (normal +z unless given).
CompensationPoints points_at(std::vector<Eigen::Vector3d> at,
                             const Eigen::Vector3d& normal = Eigen::Vector3d::UnitZ()) {
  CompensationPoints c;
  c.positions_mm = std::move(at);
  c.normals.assign(c.positions_mm.size(), normal);
  c.surface_ids.assign(c.positions_mm.size(), 0);
  c.triangles.assign(c.positions_mm.size(), 0);
  return c;
}

// Distance from a point on the surface of the box [lo, lo + size] to the
// nearest box edge.
double distance_to_box_edge(const Eigen::Vector3d& p, const Eigen::Vector3d& lo,
                            const Eigen::Vector3d& size) {
  double best = INFINITY;
  for (int axis = 0; axis < 3; ++axis) {
    const double d = std::min(p[axis] - lo[axis], lo[axis] + size[axis] - p[axis]);
    if (d > 1e-9) best = std::min(best, d);  // on a face normal to `axis`, d = 0
  }
  return best;
}

TEST(RayErrorVectors, ConstantOffsetIsRecoveredExactly) {
  const Eigen::Vector3d lo(-10, -10, -5), size(20, 20, 10);
  const TriangleMesh nominal = box(lo, size, 10);
  // The part came out 0.1 mm oversize on every face; the scan is triangulated
  // differently from the nominal.
  const TriangleMesh scan =
      box(lo - Eigen::Vector3d::Constant(0.1), size + Eigen::Vector3d::Constant(0.2), 13);
  const CompensationPoints c = sample_compensation_points(nominal, segment_surfaces(nominal), 1.0);
  const ErrorVectors e = error_vectors_by_rays(nominal, c, RayScene(scan));
  std::size_t valid = 0;
  for (std::size_t i = 0; i < c.size(); ++i) {
    const double to_edge = distance_to_box_edge(c.positions_mm[i], lo, size);
    if (to_edge <= 0.5) {
      EXPECT_EQ(e.status[i], ErrorStatus::kNominalEdge) << i;
      continue;
    }
    ASSERT_EQ(e.status[i], ErrorStatus::kValid) << i;
    ++valid;
    EXPECT_NEAR(e.normal_mm[i], 0.1, 1e-9);
    EXPECT_NEAR((e.vectors_mm[i] - 0.1 * c.normals[i]).norm(), 0.0, 1e-9);
  }
  EXPECT_GT(valid, c.size() * 8 / 10);
}

TEST(RayErrorVectors, LinearErrorIsRecoveredExactly) {
  const TriangleMesh nominal = plate(40, 20, 40, 20, [](double, double) { return 0.0; });
  auto error = [](double x, double) { return 0.02 + 0.005 * x; };  // 0.02 … 0.22 mm
  const TriangleMesh scan = moved(
      plate(42, 22, 17, 9, [&](double x, double y) { return error(x - 1, y - 1); }), {-1, -1, 0});
  const CompensationPoints c = compensation_points_at_vertices(
      nominal, std::vector<std::int32_t>(nominal.triangles.size(), 0));
  const ErrorVectors e = error_vectors_by_rays(nominal, c, RayScene(scan));
  std::size_t valid = 0;
  for (std::size_t i = 0; i < c.size(); ++i) {
    const Eigen::Vector3d& p = c.positions_mm[i];
    const bool border = p.x() == 0 || p.x() == 40 || p.y() == 0 || p.y() == 20;
    if (border) {  // the plate's open boundary is an edge
      EXPECT_EQ(e.status[i], ErrorStatus::kNominalEdge);
      continue;
    }
    ASSERT_EQ(e.status[i], ErrorStatus::kValid) << i;
    ++valid;
    EXPECT_NEAR(e.normal_mm[i], error(p.x(), p.y()), 1e-9) << p.transpose();
  }
  EXPECT_EQ(valid, 39u * 19u);
}

TEST(RayErrorVectors, BendingLineOfACantilever) {
  // Top face of a beam clamped at x = 0 that the cutting force bent away:
  // w(x) = w_tip · x²(3L − x) / (2L³).
  const double L = 40.0, w_tip = 0.3;
  auto w = [&](double x) { return w_tip * x * x * (3 * L - x) / (2 * L * L * L); };
  const TriangleMesh nominal = plate(L, 20, 20, 10, [](double, double) { return 0.0; });
  const TriangleMesh scan =
      moved(plate(L + 2, 22, 168, 88, [&](double x, double) { return w(x - 1); }), {-1, -1, 0});
  const CompensationPoints c = sample_compensation_points(
      nominal, std::vector<std::int32_t>(nominal.triangles.size(), 0), 0.8);
  const ErrorVectors e = error_vectors_by_rays(nominal, c, RayScene(scan));
  std::size_t valid = 0;
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (!e.valid(i)) continue;
    ++valid;
    // The scan is piecewise linear at 0.25 mm: chord error ≤ h²·max|w''|/8 = 4.4e-6 mm.
    EXPECT_NEAR(e.normal_mm[i], w(c.positions_mm[i].x()), 1e-5);
  }
  EXPECT_GT(valid, c.size() * 8 / 10);
  const ErrorVectorSummary s = summarize(e);
  EXPECT_EQ(s.valid, valid);
  EXPECT_EQ(s.by_status[static_cast<int>(ErrorStatus::kNominalEdge)], c.size() - valid);
  EXPECT_NEAR(s.max_length_mm, w(39.5), 0.01);
}

TEST(RayErrorVectors, RigidMisalignmentIsRemovedByRegistration) {
  const Eigen::Vector3d lo(-20, -15, -10), size(40, 30, 20);
  const TriangleMesh nominal = box(lo, size, 8);
  // 0.05 mm oversize everywhere, scanned out of place.
  TriangleMesh scan =
      box(lo - Eigen::Vector3d::Constant(0.05), size + Eigen::Vector3d::Constant(0.1), 60);
  transform_points(test_geo::rigid({1, 1, 0}, 0.6, {0.3, -0.2, 0.25}), scan.vertices_mm);

  const IcpResult reg = register_scan(nominal, scan.vertices_mm);
  ASSERT_TRUE(reg.converged);
  transform_points(reg.scan_to_nominal, scan.vertices_mm);
  const CompensationPoints c = sample_compensation_points(nominal, segment_surfaces(nominal), 2.0);
  ErrorVectors e = error_vectors_by_rays(nominal, c, RayScene(scan));
  std::size_t valid = 0;
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (!e.valid(i)) continue;
    ++valid;
    EXPECT_NEAR(e.normal_mm[i], 0.05, 0.002) << i;
  }
  EXPECT_GT(valid, c.size() * 8 / 10);
}

TEST(RayErrorVectors, RigidMisalignmentIsRemovedByRigidBodyMotionRemoval) {
  const Eigen::Vector3d lo(-20, -15, -10), size(40, 30, 20);
  const TriangleMesh nominal = box(lo, size, 8);
  TriangleMesh scan =
      box(lo - Eigen::Vector3d::Constant(0.05), size + Eigen::Vector3d::Constant(0.1), 60);
  transform_points(test_geo::rigid({0, 1, 1}, 0.1, {0.02, -0.03, 0.04}), scan.vertices_mm);
  const CompensationPoints c = sample_compensation_points(nominal, segment_surfaces(nominal), 2.0);
  ErrorVectors e = error_vectors_by_rays(nominal, c, RayScene(scan));
  const std::vector<std::uint8_t> use = e.valid_mask();
  const RigidBodyMotion m = fit_rigid_body_motion(c.positions_mm, e.vectors_mm,
                                                  RigidBodyFit::kNormalComponents, use, c.normals);
  EXPECT_GT(m.rms_before_mm, m.rms_after_mm);
  remove_rigid_body_motion(m, RigidBodyFit::kNormalComponents, c.positions_mm, e.vectors_mm,
                           c.normals);
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (!e.valid(i)) continue;
    // A uniform oversize of a closed box has no rigid part, so it stays;
    // what is left of the misalignment is second order (angle² · size).
    EXPECT_NEAR(e.vectors_mm[i].dot(c.normals[i]), 0.05, 0.001) << i;
  }
}

TEST(RayErrorVectors, NoHitWhereTheScanHasAHole) {
  const TriangleMesh nominal = plate(20, 20, 10, 10, [](double, double) { return 0.0; });
  TriangleMesh scan =
      moved(plate(24, 24, 48, 48, [](double, double) { return 0.05; }), {-2, -2, 0});
  std::erase_if(scan.triangles, [&](const Triangle& t) {
    const Eigen::Vector3d c =
        (scan.vertices_mm[t[0]] + scan.vertices_mm[t[1]] + scan.vertices_mm[t[2]]) / 3;
    return std::abs(c.x() - 10) < 2 && std::abs(c.y() - 10) < 2;
  });
  const CompensationPoints c = points_at({{10, 10, 0}, {15, 15, 0}});
  const ErrorVectors e = error_vectors_by_rays(nominal, c, RayScene(scan));
  EXPECT_EQ(e.status[0], ErrorStatus::kNoHit);
  EXPECT_EQ(e.status[1], ErrorStatus::kValid);
  EXPECT_NEAR(e.normal_mm[1], 0.05, 1e-12);
  // Also no hit when the surface is beyond the search distance.
  RayMethodOptions near;
  near.max_distance_mm = 0.04;
  EXPECT_EQ(error_vectors_by_rays(nominal, c, RayScene(scan), near).status[1], ErrorStatus::kNoHit);
}

TEST(RayErrorVectors, GrazingHitsAreInvalid) {
  const TriangleMesh nominal = plate(20, 20, 10, 10, [](double, double) { return 0.0; });
  const CompensationPoints c = points_at({{10, 10, 0}});
  for (double tilt_deg : {50.0, 70.0}) {
    // A scanned surface through (10, 10, 0.1) tilted about y.
    const double slope = std::tan(tilt_deg * M_PI / 180);
    const TriangleMesh scan = moved(
        plate(2, 20, 4, 10, [&](double x, double) { return 0.1 + slope * (x - 1); }), {9, 0, 0});
    const ErrorVectors e = error_vectors_by_rays(nominal, c, RayScene(scan));
    if (tilt_deg < 60) {
      ASSERT_EQ(e.status[0], ErrorStatus::kValid);
      EXPECT_NEAR(e.normal_mm[0], 0.1, 1e-12);
    } else {
      EXPECT_EQ(e.status[0], ErrorStatus::kGrazing);
    }
  }
}

TEST(RayErrorVectors, FarSideOfAWallIsABackFace) {
  const TriangleMesh nominal = plate(20, 20, 10, 10, [](double, double) { return 0.0; });
  TriangleMesh scan =
      moved(plate(24, 24, 12, 12, [](double, double) { return -0.2; }), {-2, -2, 0});
  for (Triangle& t : scan.triangles)
    std::swap(t[1], t[2]);  // facing −z: the underside of a wall
  const CompensationPoints c = points_at({{10, 10, 0}});
  EXPECT_EQ(error_vectors_by_rays(nominal, c, RayScene(scan)).status[0], ErrorStatus::kBackFace);
  RayMethodOptions any_side;
  any_side.reject_back_faces = false;
  const ErrorVectors e = error_vectors_by_rays(nominal, c, RayScene(scan), any_side);
  ASSERT_EQ(e.status[0], ErrorStatus::kValid);
  EXPECT_NEAR(e.normal_mm[0], -0.2, 1e-12);
}

TEST(RayErrorVectors, PointsOnOrNearNominalEdgesAreInvalid) {
  const Eigen::Vector3d lo(0, 0, 0), size(20, 20, 10);
  const TriangleMesh nominal = box(lo, size, 4);
  const TriangleMesh scan =
      box(lo - Eigen::Vector3d::Constant(0.1), size + Eigen::Vector3d::Constant(0.2), 4);
  // On the top face: a corner, a point on an edge, 0.4 mm and 0.6 mm from
  // the edge x = 20.
  const CompensationPoints c = points_at({{20, 20, 10}, {20, 7, 10}, {19.6, 7, 10}, {19.4, 7, 10}});
  const RayScene s(scan);
  const ErrorVectors e = error_vectors_by_rays(nominal, c, s);
  EXPECT_EQ(e.status[0], ErrorStatus::kNominalEdge);
  EXPECT_EQ(e.status[1], ErrorStatus::kNominalEdge);
  EXPECT_EQ(e.status[2], ErrorStatus::kNominalEdge);
  EXPECT_EQ(e.status[3], ErrorStatus::kValid);
  RayMethodOptions on_edge_only;
  on_edge_only.edge_exclusion_mm = 0.0;
  const ErrorVectors f = error_vectors_by_rays(nominal, c, s, on_edge_only);
  EXPECT_EQ(f.status[0], ErrorStatus::kNominalEdge);
  EXPECT_EQ(f.status[1], ErrorStatus::kNominalEdge);
  EXPECT_EQ(f.status[2], ErrorStatus::kValid);
  // A 20° fold is not sharp under the default 30°.
  const TriangleMesh folded = plate(20, 10, 20, 10, [](double x, double) {
    return x > 10 ? (x - 10) * std::tan(M_PI / 9) : 0.0;
  });
  const ErrorVectors g =
      error_vectors_by_rays(folded, points_at({{10, 5, 0}}), RayScene(moved(folded, {0, 0, 0.05})));
  EXPECT_EQ(g.status[0], ErrorStatus::kValid);
}

TEST(RayErrorVectors, BatchModesAgree) {
  const TriangleMesh nominal = box({-10, -10, -5}, {20, 20, 10}, 10);
  const TriangleMesh scan = box({-10.1, -10.05, -5.02}, {20.15, 20.1, 10.07}, 17);
  const CompensationPoints c = sample_compensation_points(nominal, segment_surfaces(nominal), 0.7);
  RayMethodOptions o;
  const ErrorVectors a = error_vectors_by_rays(nominal, c, RayScene(scan), o);
  o.batch = RayBatch::kPacket16;
  const ErrorVectors b = error_vectors_by_rays(nominal, c, RayScene(scan), o);
  o.batch = RayBatch::kStream;
  const ErrorVectors d = error_vectors_by_rays(nominal, c, RayScene(scan), o);
  EXPECT_EQ(a.vectors_mm, b.vectors_mm);
  EXPECT_EQ(a.vectors_mm, d.vectors_mm);
  EXPECT_EQ(a.status, b.status);
  EXPECT_EQ(a.status, d.status);
}

}  // namespace
}  // namespace truecut::offline
