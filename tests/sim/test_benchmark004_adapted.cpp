// benchmark004's program generated for an adapted geometry (DriveSurface,
// the model-adaptation route): the adapted mesh is planted here as the
// nominal mesh with every vertex moved by a known displacement D(v), normal
// to every surface of the drawing (a tangential move shifts the facets and
// with them the faceting, which is not what is tested here):
//   z <= 35: D = (s·x, s·y, b·(z − 35))   walls radially, faces axially
//   z >= 35: D = s·(v − C)                the hemisphere about its centre C
// continuous at z = 35, so the offset the tool path must follow is D(p)·n at
// a surface point p with normal n, computed from the drawing, not from the
// generator.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "benchmark004_drawing.hpp"
#include "part_test_support.hpp"
#include "truecut/interp/operations.hpp"
#include "truecut/sim/benchmark_parts.hpp"
#include "truecut/sim/drive_surface.hpp"

using namespace truecut::sim;
using namespace truecut::sim::test::benchmark004;
using truecut::interp::ArcFeed;
using truecut::interp::CanonCall;
using truecut::interp::StraightFeed;
using truecut::sim::test::feed_end;
using truecut::sim::test::interpret;

namespace {

constexpr double kPi = std::numbers::pi;

struct Planted {
  double s, b;
  Eigen::Vector3d displacement(const Eigen::Vector3d& v) const {
    if (v.z() >= kSphereZ) return s * (v - kSphereCentre);
    return {s * v.x(), s * v.y(), b * (v.z() - kSphereZ)};
  }
  double offset(const Eigen::Vector3d& p, const Eigen::Vector3d& n) const {
    return displacement(p).dot(n);
  }
};

truecut::offline::TriangleMesh moved(const truecut::offline::TriangleMesh& nominal,
                                     const Planted& planted) {
  truecut::offline::TriangleMesh m = nominal;
  for (auto& v : m.vertices_mm)
    v += planted.displacement(v);
  return m;
}

double rho(const Eigen::Vector3d& p) {
  return std::hypot(p.x(), p.y());
}

// Offsets from a few micrometres to the 0.15 mm near the field's 0.2 mm
// limit, both signs, walls and faces moved apart or alone.
const Planted kCases[] = {{-2e-3, 1e-3}, {1e-4, 0}, {3e-3, -2e-3}, {0, 4e-4}};

}  // namespace

TEST(DriveSurface, OffsetIsThePlantedDisplacementAlongTheNormal) {
  const BenchmarkPart part = make_part(PartId::kBenchmark004, coarse());
  for (const Planted& planted : kCases) {
    const DriveSurface drive(part.mesh, moved(part.mesh, planted));
    double worst = 0;
    for (int k = 0; k < 97; ++k) {
      const double psi = 2 * kPi * (k + 0.31) / 97;
      const Eigen::Vector3d e(std::cos(psi), std::sin(psi), 0);
      const auto check = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& n) {
        worst = std::max(worst, std::abs(drive.offset_mm(p, n) - planted.offset(p, n)));
      };
      check(kBaseR * e + Eigen::Vector3d(0, 0, 7.3), e);
      check(kStepR * e + Eigen::Vector3d(0, 0, 21.9), e);
      check(kCollarR * e + Eigen::Vector3d(0, 0, 32.2), e);
      check(45.1 * e + Eigen::Vector3d(0, 0, kStep1Z), Eigen::Vector3d::UnitZ());
      check(29.4 * e + Eigen::Vector3d(0, 0, kStep2Z), Eigen::Vector3d::UnitZ());
      const double phi = (5 + 80.0 * k / 97) * kPi / 180;
      const Eigen::Vector3d u(std::sin(phi) * e.x(), std::sin(phi) * e.y(), std::cos(phi));
      check(kSphereCentre + kSphereR * u, u);
    }
    EXPECT_LT(worst, 0.5e-3) << "s " << planted.s;
    EXPECT_EQ(drive.misses(), 0u);
  }
}

TEST(DriveSurface, MissesCountAndGiveNoOffsetOffTheSurface) {
  const BenchmarkPart part = make_part(PartId::kBenchmark004, coarse());
  const DriveSurface drive(part.mesh, moved(part.mesh, kCases[0]));
  // 2 mm outside the base cylinder: nothing within reach.
  EXPECT_EQ(drive.offset_mm({kBaseR + 2, 0, 7}, Eigen::Vector3d::UnitX()), 0.0);
  EXPECT_EQ(drive.misses(), 1u);
  EXPECT_THROW(DriveSurface(truecut::offline::TriangleMesh{}, part.mesh), std::invalid_argument);
  EXPECT_THROW(make_part(PartId::kImplant, coarse(), drive), std::invalid_argument);
}

// Every feed move of the driven program on a finished surface sits where the
// planted adapted surface asks: walls at R + r + offset, faces at z + offset,
// the ball centre at R + r_b + offset from the sphere's centre.
TEST(Benchmark004Adapted, PassesFollowThePlantedAdaptedSurface) {
  const PartOptions o = coarse();
  const BenchmarkPart nominal = make_part(PartId::kBenchmark004, o);
  const double r = nominal.metadata.tools[0].radius_mm, rb = nominal.metadata.tools[1].radius_mm;
  // The program is written to 0.1 µm; the mesh's faceting adds less than the
  // DriveSurface test's bound.
  constexpr double kTolMm = 0.6e-3;
  for (const Planted& planted : kCases) {
    const DriveSurface drive(nominal.mesh, moved(nominal.mesh, planted));
    const BenchmarkPart part = make_part(PartId::kBenchmark004, o, drive);
    EXPECT_EQ(part.mesh.vertices_mm, nominal.mesh.vertices_mm) << "the nominal stays";
    const auto program = interpret(part);

    int wall_points = 0;
    for (const CanonCall& c : truecut::interp::moves_of_operation(program, "WALLS")) {
      EXPECT_FALSE(std::holds_alternative<ArcFeed>(c.op)) << "circles become G1 moves";
      const auto* end = feed_end(c);
      if (!end) continue;
      const Eigen::Vector3d p(end->x, end->y, end->z);
      for (double R : {kCollarR, kStepR, kBaseR}) {
        if (std::abs(rho(p) - (R + r)) > 0.3) continue;
        const Eigen::Vector3d n = Eigen::Vector3d(p.x(), p.y(), 0).normalized();
        // The planted offset does not vary along a wall's height.
        EXPECT_NEAR(rho(p), R + r + planted.offset(R * n + Eigen::Vector3d(0, 0, p.z()), n), kTolMm)
            << p.transpose();
        ++wall_points;
      }
    }
    EXPECT_GT(wall_points, 1000);

    int face_points = 0;
    for (const CanonCall& c : truecut::interp::moves_of_operation(program, "STEP_FACES")) {
      const auto* f = std::get_if<StraightFeed>(&c.op);
      if (!f) continue;
      const Eigen::Vector3d p(f->end.x, f->end.y, f->end.z);
      for (double z : {kStep1Z, kStep2Z}) {
        if (std::abs(p.z() - z) > 0.3) continue;
        EXPECT_NEAR(p.z(), z + planted.offset({0, 0, z}, Eigen::Vector3d::UnitZ()), kTolMm);
        ++face_points;
      }
    }
    EXPECT_GT(face_points, 1000);

    int sphere_points = 0;
    const auto on_sphere = [&](const Eigen::Vector3d& centre) {
      const Eigen::Vector3d u = (centre - kSphereCentre).normalized();
      const double d = (centre - kSphereCentre).norm();
      if (std::abs(d - (kSphereR + rb)) > 0.3) return;
      EXPECT_NEAR(d, kSphereR + rb + planted.offset(kSphereCentre + kSphereR * u, u), kTolMm)
          << "u " << u.transpose();
      ++sphere_points;
    };
    for (const CanonCall& c : truecut::interp::moves_of_operation(program, "HEMISPHERE_3AXIS"))
      if (const auto* end = feed_end(c)) on_sphere({end->x, end->y, end->z + rb});
    for (const CanonCall& c : truecut::interp::moves_of_operation(program, "HEMISPHERE_CAP_5AXIS"))
      if (const auto* end = feed_end(c))
        on_sphere(Eigen::Vector3d(end->x, end->y, end->z) +
                  rb * truecut::sim::test::tool_axis(end->a, end->c));
    EXPECT_GT(sphere_points, 1000);
    EXPECT_EQ(drive.misses(), 0u) << "s " << planted.s;
  }
}
