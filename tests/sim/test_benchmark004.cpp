// benchmark004: the stepped cylinder with a hemisphere — closed outward mesh
// on the analytic surfaces with the analytic volume, a near-net stock, and a
// program that truecut's interpreter reads whose tool paths touch the
// nominal surfaces by the tool radius and never cut into them.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <set>

#include "benchmark004_drawing.hpp"
#include "part_test_support.hpp"
#include "test_paths.hpp"
#include "truecut/interp/operations.hpp"
#include "truecut/sim/benchmark_parts.hpp"

using namespace truecut::sim;
using namespace truecut::sim::test::benchmark004;
using truecut::interp::ArcFeed;
using truecut::interp::CanonCall;
using truecut::interp::CanonProgram;
using truecut::sim::test::feed_end;
using truecut::sim::test::interpret;

namespace {

constexpr double kPi = std::numbers::pi;

double analytic_volume() {
  return kPi * (kBaseR * kBaseR * kStep1Z + kStepR * kStepR * (kStep2Z - kStep1Z) +
                kCollarR * kCollarR * (kSphereZ - kStep2Z)) +
         2.0 / 3.0 * kPi * kSphereR * kSphereR * kSphereR;
}

double rho(const Eigen::Vector3d& p) {
  return std::hypot(p.x(), p.y());
}

// Distance in the (ρ, z) half-plane from q to the part's profile (boundary).
double distance_to_profile(double r, double z) {
  const auto seg = [&](double r0, double z0, double r1, double z1) {
    const Eigen::Vector2d a(r0, z0), b(r1, z1), q(r, z);
    const double t = std::clamp((q - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
    return (q - (a + t * (b - a))).norm();
  };
  double d = std::min({seg(0, 0, kBaseR, 0), seg(kBaseR, 0, kBaseR, kStep1Z),
                       seg(kBaseR, kStep1Z, kStepR, kStep1Z), seg(kStepR, kStep1Z, kStepR, kStep2Z),
                       seg(kStepR, kStep2Z, kCollarR, kStep2Z),
                       seg(kCollarR, kStep2Z, kCollarR, kSphereZ)});
  if (z >= kSphereZ) d = std::min(d, std::abs(std::hypot(r, z - kSphereZ) - kSphereR));
  return d;
}

bool in_stock(const PartMetadata& m, const Eigen::Vector3d& p) {
  for (const StockBox& b : m.stock) {
    if ((p.array() >= b.min_mm.array() - 1e-9).all() &&
        (p.array() <= b.max_mm.array() + 1e-9).all())
      return true;
  }
  return false;
}

}  // namespace

TEST(Benchmark004, MeshIsClosedOutwardWithinHalfAPercentOfTheAnalyticVolume) {
  for (double edge : {3.0, 2.0, 0.5}) {
    PartOptions o = coarse();
    o.mesh_edge_mm = edge;
    const BenchmarkPart part = make_part(PartId::kBenchmark004, o);
    truecut::sim::test::expect_closed_and_consistent(part.mesh);
    ASSERT_EQ(part.triangle_surface.size(), part.mesh.triangles.size());
    const double v = signed_volume_mm3(part.mesh);  // > 0: normals point outwards
    EXPECT_LT(std::abs(v - analytic_volume()), 5e-3 * analytic_volume()) << "edge " << edge;
    EXPECT_LT(v, analytic_volume()) << "inscribed polygons are smaller";
  }
}

TEST(Benchmark004, EveryTriangleLiesOnItsSurfaceAndFacesOutwards) {
  const BenchmarkPart part = make_part(PartId::kBenchmark004, coarse());
  std::set<int> seen;
  for (std::size_t i = 0; i < part.mesh.triangles.size(); ++i) {
    const int s = part.triangle_surface[i];
    seen.insert(s);
    const auto& t = part.mesh.triangles[i];
    const Eigen::Vector3d a = part.mesh.vertices_mm[t[0]], b = part.mesh.vertices_mm[t[1]],
                          c = part.mesh.vertices_mm[t[2]];
    const Eigen::Vector3d n = (b - a).cross(c - a).normalized();
    const Eigen::Vector3d m = (a + b + c) / 3;
    Eigen::Vector3d want;  // the analytic outward normal at the centroid
    for (const Eigen::Vector3d& v : {a, b, c}) {
      switch (s) {
        case 1:
        case 2:
          EXPECT_NEAR((v - kSphereCentre).norm(), kSphereR, 1e-9);
          EXPECT_GE(v.z(), kSphereZ - 1e-9);
          break;
        case 3:
          EXPECT_NEAR(rho(v), kCollarR, 1e-9);
          break;
        case 4:
          EXPECT_NEAR(v.z(), kStep2Z, 1e-12);
          break;
        case 5:
          EXPECT_NEAR(rho(v), kStepR, 1e-9);
          break;
        case 6:
          EXPECT_NEAR(v.z(), kStep1Z, 1e-12);
          break;
        case 7:
          EXPECT_NEAR(rho(v), kBaseR, 1e-9);
          break;
        case 8:
          EXPECT_NEAR(v.z(), 0, 1e-12);
          break;
      }
    }
    if (s <= 2) want = (m - kSphereCentre).normalized();
    if (s == 3 || s == 5 || s == 7) want = Eigen::Vector3d(m.x(), m.y(), 0).normalized();
    if (s == 4 || s == 6) want = Eigen::Vector3d::UnitZ();
    if (s == 8) want = -Eigen::Vector3d::UnitZ();
    EXPECT_GT(n.dot(want), 0.95) << "surface " << s;
    // The cap ends at 30° from the pole.
    const double polar_deg =
        std::acos(std::clamp((m - kSphereCentre).normalized().z(), -1.0, 1.0)) * 180 / kPi;
    if (s == 1) {
      EXPECT_GT(polar_deg, 30.0);
    }
    if (s == 2) {
      EXPECT_LT(polar_deg, 30.0);
    }
  }
  EXPECT_EQ(seen, (std::set<int>{1, 2, 3, 4, 5, 6, 7, 8}));
  int compensated = 0;
  for (const PartSurface& s : part.metadata.surfaces)
    compensated += s.compensate;
  EXPECT_EQ(compensated, 7) << "all but the bottom";
}

TEST(Benchmark004, StockCoversHalfAMillimetreAndStaysWithinTheAllowance) {
  const BenchmarkPart part = make_part(PartId::kBenchmark004, coarse());
  const PartMetadata& m = part.metadata;
  EXPECT_LT(m.stock.size(), 500u);
  // Points 0.5 mm out along the normal of every machined surface (and round
  // the convex step edges) are inside the stock.
  int outside = 0, samples = 0;
  const auto check = [&](const Eigen::Vector3d& p) {
    ++samples;
    if (!in_stock(m, p)) ++outside;
  };
  const double a = 0.5 - 1e-6;
  for (int k = 0; k < 360; ++k) {
    const double psi = 2 * kPi * (k + 0.37) / 360;
    const Eigen::Vector3d e(std::cos(psi), std::sin(psi), 0);
    for (int i = 0; i <= 20; ++i) {
      const double t = i / 20.0;
      check((kBaseR + a) * e + Eigen::Vector3d(0, 0, t * kStep1Z));
      check((kStepR + a) * e + Eigen::Vector3d(0, 0, kStep1Z + t * (kStep2Z - kStep1Z)));
      check((kCollarR + a) * e + Eigen::Vector3d(0, 0, kStep2Z + t * (kSphereZ - kStep2Z)));
      check((kStepR + t * (kBaseR - kStepR)) * e + Eigen::Vector3d(0, 0, kStep1Z + a));
      check((kCollarR + t * (kStepR - kCollarR)) * e + Eigen::Vector3d(0, 0, kStep2Z + a));
      const double phi = t * kPi / 2;
      check(kSphereCentre + (kSphereR + a) * Eigen::Vector3d(std::sin(phi) * e.x(),
                                                             std::sin(phi) * e.y(), std::cos(phi)));
      const double q = t * kPi / 2;  // round the convex edges
      check((kBaseR + a * std::cos(q)) * e + Eigen::Vector3d(0, 0, kStep1Z + a * std::sin(q)));
      check((kStepR + a * std::cos(q)) * e + Eigen::Vector3d(0, 0, kStep2Z + a * std::sin(q)));
    }
  }
  EXPECT_EQ(outside, 0) << "of " << samples;
  // Every box corner lies within 1 mm of the part (1.5 mm above the sphere's
  // equator), and no box reaches below the bottom face.
  double worst_cyl = 0, worst_dome = 0;
  for (const StockBox& b : m.stock) {
    EXPECT_GE(b.min_mm.z(), 0.0);
    for (int c = 0; c < 8; ++c) {
      const Eigen::Vector3d p((c & 1) ? b.max_mm.x() : b.min_mm.x(),
                              (c & 2) ? b.max_mm.y() : b.min_mm.y(),
                              (c & 4) ? b.max_mm.z() : b.min_mm.z());
      const double d = distance_to_profile(rho(p), p.z());
      (b.min_mm.z() >= kSphereZ - 1e-9 ? worst_dome : worst_cyl) =
          std::max(b.min_mm.z() >= kSphereZ - 1e-9 ? worst_dome : worst_cyl, d);
    }
  }
  EXPECT_LE(worst_cyl, 1.0 + 1e-9);
  EXPECT_LE(worst_dome, 1.5 + 1e-9);
  EXPECT_GT(worst_cyl, 0.8) << "the stock is near-net, not the part itself";
}

TEST(Benchmark004, ProgramInterpretsWithNamedOperationsAndTools) {
  const BenchmarkPart part = make_part(PartId::kBenchmark004, coarse());
  const CanonProgram program = interpret(part);
  EXPECT_EQ(truecut::interp::operation_names(program),
            (std::vector<std::string>{"WALLS", "STEP_FACES", "HEMISPHERE_3AXIS",
                                      "HEMISPHERE_CAP_5AXIS"}));
  for (const PartOperation& op : part.metadata.operations) {
    const auto moves = truecut::interp::moves_of_operation(program, op.name);
    ASSERT_FALSE(moves.empty()) << op.name;
    for (const CanonCall& c : moves) {
      if (feed_end(c)) {
        EXPECT_EQ(c.context.tool, op.tool) << op.name;
        EXPECT_EQ(c.context.tcp, op.strategy == "5-axis") << op.name;
      }
    }
  }
}

TEST(Benchmark004, WallsAreFullClimbCirclesOneToolRadiusOutAtEveryLevel) {
  const BenchmarkPart part = make_part(PartId::kBenchmark004, coarse());
  const double r = part.metadata.tools[0].radius_mm;
  struct Wall {
    double radius, bottom, top;
    std::set<long> levels;
  };
  std::vector<Wall> walls = {
      {kCollarR, kStep2Z, kSphereZ, {}}, {kStepR, kStep1Z, kStep2Z, {}}, {kBaseR, 0, kStep1Z, {}}};
  for (const CanonCall& c : truecut::interp::moves_of_operation(interpret(part), "WALLS")) {
    const auto* end = feed_end(c);
    if (!end) continue;
    const Eigen::Vector3d p(end->x, end->y, end->z);
    // Never closer than R to any wall below the tool tip's level.
    for (const Wall& w : walls) {
      if (p.z() < w.top - 1e-9) {
        EXPECT_GE(rho(p), w.radius + r - 1e-9) << p.transpose();
      }
    }
    if (const auto* arc = std::get_if<ArcFeed>(&c.op)) {
      EXPECT_LT(arc->rotation, 0) << "clockwise: climb milling outside";
      EXPECT_NEAR(arc->center.x, 0, 1e-12);
      EXPECT_NEAR(arc->center.y, 0, 1e-12);
      bool matched = false;
      for (Wall& w : walls) {
        if (std::abs(rho(p) - (w.radius + r)) < 1e-9) {
          matched = true;
          EXPECT_GE(p.z(), w.bottom - 1e-9);
          EXPECT_LT(p.z(), w.top);
          w.levels.insert(std::lround(p.z() * 1000));
        }
      }
      EXPECT_TRUE(matched) << rho(p);
    }
  }
  // Step-down 2 mm: collar 33, 31, 30; step-1 wall 28 … 16, 15; cylinder 13 … 1, 0.
  EXPECT_EQ(walls[0].levels, (std::set<long>{30000, 31000, 33000}));
  EXPECT_EQ(walls[1].levels.size(), 8u);
  EXPECT_EQ(*walls[1].levels.begin(), 15000);
  EXPECT_EQ(walls[2].levels.size(), 8u);
  EXPECT_EQ(*walls[2].levels.begin(), 0);
}

TEST(Benchmark004, StepFacesAreCoveredByTheFlatBottomAtTheirHeight) {
  const BenchmarkPart part = make_part(PartId::kBenchmark004, coarse());
  const double r = part.metadata.tools[0].radius_mm;
  std::map<long, std::vector<double>> rings;  // z → circle radii
  for (const CanonCall& c : truecut::interp::moves_of_operation(interpret(part), "STEP_FACES")) {
    const auto* arc = std::get_if<ArcFeed>(&c.op);
    if (!arc) continue;
    if (std::abs(arc->end.z - kStep2Z) > 1e-9 && std::abs(arc->end.z - kStep1Z) > 1e-9) continue;
    rings[std::lround(arc->end.z * 1000)].push_back(std::hypot(arc->end.x, arc->end.y));
  }
  ASSERT_EQ(rings.size(), 2u);
  const auto covers = [&](std::vector<double> radii, double inner, double outer) {
    std::sort(radii.begin(), radii.end());
    EXPECT_NEAR(radii.front() - r, inner, 1e-9) << "flank touches the inner wall";
    EXPECT_GE(radii.back() + r, outer - 1e-9);
    for (std::size_t k = 1; k < radii.size(); ++k)
      EXPECT_LE(radii[k] - radii[k - 1], 0.8 + 1e-9) << "stepover";
  };
  covers(rings[std::lround(kStep2Z * 1000)], kCollarR, kStepR);
  EXPECT_LE(*std::max_element(rings[30000].begin(), rings[30000].end()) + r, kStepR + 1e-9)
      << "no gouge in the step-1 wall";
  covers(rings[std::lround(kStep1Z * 1000)], kStepR, kBaseR);
}

TEST(Benchmark004, Hemisphere3AxisBallCentreRunsOneBallRadiusFromTheSphere) {
  const BenchmarkPart part = make_part(PartId::kBenchmark004, coarse());
  const double rb = part.metadata.tools[1].radius_mm;
  double polar_min = 180, polar_max = 0;
  int on_surface = 0;
  for (const CanonCall& c :
       truecut::interp::moves_of_operation(interpret(part), "HEMISPHERE_3AXIS")) {
    const auto* end = feed_end(c);
    if (!end) continue;
    EXPECT_FALSE(c.context.tcp);
    const Eigen::Vector3d centre(end->x, end->y, end->z + rb);
    const double d = (centre - kSphereCentre).norm();
    EXPECT_GE(d, kSphereR + rb - 1e-4) << "gouge";
    EXPECT_GE(end->z, kStep2Z) << "the ball stays above the step-2 face";
    if (std::abs(d - (kSphereR + rb)) < 1e-4) {
      ++on_surface;
      const double polar = std::acos((centre - kSphereCentre).z() / d) * 180 / kPi;
      polar_min = std::min(polar_min, polar);
      polar_max = std::max(polar_max, polar);
    }
    if (const auto* arc = std::get_if<ArcFeed>(&c.op)) {
      EXPECT_LT(arc->rotation, 0);
      EXPECT_NEAR(std::hypot(arc->center.x, arc->center.y), 0, 1e-12);
    }
  }
  EXPECT_GT(on_surface, 30);
  EXPECT_NEAR(polar_max, 90.0, 1e-6) << "down to the equator";
  EXPECT_NEAR(polar_min, 30.0, 1e-3) << "up to the cap";
}

TEST(Benchmark004, CapSpiralsToThePoleWithTheAxisTiltedFromTheNormal) {
  const BenchmarkPart part = make_part(PartId::kBenchmark004, coarse());
  const double rb = part.metadata.tools[1].radius_mm;
  const auto moves = truecut::interp::moves_of_operation(interpret(part), "HEMISPHERE_CAP_5AXIS");
  int on_surface = 0, lifted = 0;
  double polar_last = 90, max_step = 0, c_prev = -1e9;
  const truecut::interp::Axes6* prev = nullptr;
  for (const CanonCall& c : moves) {
    const auto* end = feed_end(c);
    if (!end) continue;
    EXPECT_TRUE(c.context.tcp);
    EXPECT_GE(end->a, part.metadata.a_min_deg);
    EXPECT_LE(end->a, part.metadata.a_max_deg);
    const Eigen::Vector3d axis = truecut::sim::test::tool_axis(end->a, end->c);
    const Eigen::Vector3d centre = Eigen::Vector3d(end->x, end->y, end->z) + rb * axis;
    const double d = (centre - kSphereCentre).norm();
    EXPECT_GE(d, kSphereR + rb - 2e-4) << "gouge";
    if (std::abs(d - (kSphereR + rb)) < 2e-4) {
      ++on_surface;
      const Eigen::Vector3d n = (centre - kSphereCentre) / d;
      const double tilt = std::acos(std::clamp(axis.dot(n), -1.0, 1.0)) * 180 / kPi;
      EXPECT_NEAR(tilt, 20.0, 0.05) << "the ball cuts with its side, not its tip";
      polar_last = std::acos(n.z()) * 180 / kPi;
      EXPECT_GE(end->c, c_prev - 1e-9) << "C turns on in one direction";
      c_prev = end->c;
    } else {
      ++lifted;
    }
    if (prev)
      max_step = std::max({max_step, std::abs(end->a - prev->a), std::abs(end->c - prev->c)});
    prev = end;
  }
  EXPECT_GT(on_surface, 1000);
  EXPECT_LE(lifted, 1) << "the retract along the axis";
  EXPECT_LT(polar_last, 0.01) << "the spiral ends at the pole";
  EXPECT_LT(max_step, 1.5);
  EXPECT_GT(c_prev, 360.0 * 10) << "one turn of C per stepover";
}

TEST(Benchmark004, GenerationIsDeterministicToTheByte) {
  const auto dir_a = truecut::test::scratch_dir() / "a";
  const auto dir_b = truecut::test::scratch_dir() / "b";
  write_part(make_part(PartId::kBenchmark004, coarse()), dir_a);
  write_part(make_part(PartId::kBenchmark004, coarse()), dir_b);
  for (const char* f : {"nominal.stl", "program.ngc", "tools.tbl", "part.json", "machine.json",
                        "machine_ideal.json"}) {
    const std::string a = truecut::test::read_file(dir_a / f);
    EXPECT_FALSE(a.empty()) << f;
    EXPECT_EQ(a, truecut::test::read_file(dir_b / f)) << f;
  }
}
