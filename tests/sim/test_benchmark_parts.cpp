// Benchmark parts: closed outward meshes of the right size, programs that
// truecut's interpreter reads, tool paths on the nominal surfaces offset by
// the tool, continuous A/C in the 5-axis operation, determinism.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <set>

#include "part_test_support.hpp"
#include "test_paths.hpp"
#include "truecut/interp/interpreter.hpp"
#include "truecut/interp/operations.hpp"
#include "truecut/offline/stl_io.hpp"
#include "truecut/sim/benchmark_parts.hpp"

using namespace truecut::sim;
using truecut::interp::ArcFeed;
using truecut::interp::CanonCall;
using truecut::interp::CanonProgram;
using truecut::interp::StraightFeed;
using truecut::sim::test::expect_closed_and_consistent;
using truecut::sim::test::feed_end;
using truecut::sim::test::interpret;
using truecut::sim::test::tool_axis;

namespace {

constexpr double kPi = std::numbers::pi;

PartOptions coarse() {
  return {2.0, 0.8, 1.0, 2.0};
}

// Foot point (x, y) of p on the free-form top (Newton on the tangential part).
Eigen::Vector2d foot_on_freeform(const Eigen::Vector3d& p) {
  double x = p.x(), y = p.y();
  for (int it = 0; it < 50; ++it) {
    const Eigen::Vector3d s(x, y, freeform_height_mm(x, y));
    const Eigen::Vector3d n = freeform_normal(x, y);
    const Eigen::Vector3d d = p - s;
    const Eigen::Vector3d tangential = d - d.dot(n) * n;
    x += tangential.x();
    y += tangential.y();
    if (tangential.norm() < 1e-10) break;
  }
  return {x, y};
}

double distance_to_freeform(const Eigen::Vector3d& p) {
  const Eigen::Vector2d f = foot_on_freeform(p);
  return (p - Eigen::Vector3d(f.x(), f.y(), freeform_height_mm(f.x(), f.y()))).norm();
}

}  // namespace

TEST(BenchmarkParts, NamesRoundTrip) {
  for (PartId id : kAllParts) {
    EXPECT_EQ(part_from_name(part_name(id)), id);
  }
  EXPECT_FALSE(part_from_name("bracket").has_value());
}

TEST(BenchmarkParts, RejectsAbsurdResolution) {
  PartOptions o;
  o.stepover_mm = 0;
  EXPECT_THROW(make_part(PartId::kImplant, o), std::invalid_argument);
  o = {};
  o.mesh_edge_mm = std::nan("");
  EXPECT_THROW(make_part(PartId::kFreeform, o), std::invalid_argument);
}

TEST(ImplantPart, MeshIsClosedOutwardWithTheAnalyticVolume) {
  for (double edge : {3.0, 0.5}) {
    PartOptions o = coarse();
    o.mesh_edge_mm = edge;
    const BenchmarkPart part = make_part(PartId::kImplant, o);
    expect_closed_and_consistent(part.mesh);
    EXPECT_EQ(part.triangle_surface.size(), part.mesh.triangles.size());
    EXPECT_NEAR(signed_volume_mm3(part.mesh), 12.0 * 12.0 * 5.0 + 1.6 * 1.6 * 17.0, 1e-9);
  }
}

TEST(ImplantPart, ShaftIs1p6WideAnd17Long) {
  const BenchmarkPart part = make_part(PartId::kImplant, coarse());
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e9), hi = -lo;
  for (const auto& v : part.mesh.vertices_mm) {
    if (v.z() <= 1e-9) continue;  // base
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  EXPECT_NEAR(hi.x() - lo.x(), 1.6, 1e-12);
  EXPECT_NEAR(hi.y() - lo.y(), 1.6, 1e-12);
  EXPECT_NEAR(hi.z(), 17.0, 1e-12);
  // The shaft faces carry their surface ids: +X face triangles lie on x = 0.8.
  for (std::size_t i = 0; i < part.mesh.triangles.size(); ++i) {
    if (part.triangle_surface[i] != 1) continue;
    for (auto v : part.mesh.triangles[i])
      EXPECT_DOUBLE_EQ(part.mesh.vertices_mm[v].x(), 0.8);
  }
}

TEST(ImplantPart, ProgramParsesWithNamedOperationsAndTools) {
  const BenchmarkPart part = make_part(PartId::kImplant, coarse());
  const CanonProgram program = interpret(part);
  EXPECT_EQ(truecut::interp::operation_names(program),
            (std::vector<std::string>{"SHAFT_TOP_FACE", "SHAFT_PERIPHERAL"}));
  for (const PartOperation& op : part.metadata.operations) {
    const auto moves = truecut::interp::moves_of_operation(program, op.name);
    ASSERT_FALSE(moves.empty()) << op.name;
    for (const CanonCall& c : moves) {
      if (feed_end(c)) {
        EXPECT_EQ(c.context.tool, op.tool) << op.name;
      }
    }
  }
}

TEST(ImplantPart, FaceMillingRunsOnTheTopFaceAndCoversIt) {
  const BenchmarkPart part = make_part(PartId::kImplant, coarse());
  const auto moves = truecut::interp::moves_of_operation(interpret(part), "SHAFT_TOP_FACE");
  double y_min = 1e9, y_max = -1e9, x_min = 1e9, x_max = -1e9;
  for (const CanonCall& c : moves) {
    const auto* end = feed_end(c);
    if (!end) continue;
    EXPECT_NEAR(end->z, 17.0, 1e-9);  // flat tool tip on the nominal face
    y_min = std::min(y_min, end->y);
    y_max = std::max(y_max, end->y);
    x_min = std::min(x_min, end->x);
    x_max = std::max(x_max, end->x);
  }
  const double r = part.metadata.tools[1].radius_mm;
  EXPECT_LE(y_min, -0.8 + 1e-9);
  EXPECT_GE(y_max, 0.8 - 1e-9);
  EXPECT_LT(x_min, -0.8 - r);  // the tool leaves the face completely
  EXPECT_GT(x_max, 0.8 + r);
}

TEST(ImplantPart, PeripheralPathIsTheShaftOffsetByTheToolRadius) {
  const BenchmarkPart part = make_part(PartId::kImplant, coarse());
  const double r = part.metadata.tools[0].radius_mm;
  const auto moves = truecut::interp::moves_of_operation(interpret(part), "SHAFT_PERIPHERAL");
  // For every level: the four faces are each touched (distance exactly R),
  // and no point comes closer than R to the shaft.
  std::map<long, std::set<int>> faces_at_level;
  int arcs = 0;
  for (const CanonCall& c : moves) {
    const auto* end = feed_end(c);
    if (!end) continue;
    const double dx = std::max(std::abs(end->x) - 0.8, 0.0);
    const double dy = std::max(std::abs(end->y) - 0.8, 0.0);
    const double d = std::hypot(dx, dy);
    EXPECT_GE(d, r - 1e-9) << "gouge at " << end->x << " " << end->y << " " << end->z;
    EXPECT_GE(end->z, -1e-9);
    EXPECT_LE(end->z, 17.0);
    if (std::abs(d - r) < 1e-9) {
      const long level = std::lround(end->z * 1000);
      if (dy == 0) faces_at_level[level].insert(end->x > 0 ? 0 : 1);
      if (dx == 0) faces_at_level[level].insert(end->y > 0 ? 2 : 3);
    }
    if (const auto* arc = std::get_if<ArcFeed>(&c.op)) {
      ++arcs;
      EXPECT_LT(arc->rotation, 0);  // clockwise: climb milling outside
      EXPECT_NEAR(std::abs(arc->center.x), 0.8, 1e-9);
      EXPECT_NEAR(std::abs(arc->center.y), 0.8, 1e-9);
    }
  }
  // Levels: 15, 13, ..., 1, then 0 (step-down 2 mm).
  ASSERT_EQ(faces_at_level.size(), 9u);
  EXPECT_EQ(faces_at_level.begin()->first, 0);
  for (const auto& [level, faces] : faces_at_level)
    EXPECT_EQ(faces.size(), 4u) << level;
  EXPECT_EQ(arcs, 4 * 9);
}

TEST(FreeformPart, NormalIsTheGradientOfTheHeight) {
  const double h = 1e-6;
  for (double x : {-29.0, -7.5, 0.0, 13.0}) {
    for (double y : {-19.0, -2.0, 11.0}) {
      const double hx = (freeform_height_mm(x + h, y) - freeform_height_mm(x - h, y)) / (2 * h);
      const double hy = (freeform_height_mm(x, y + h) - freeform_height_mm(x, y - h)) / (2 * h);
      const Eigen::Vector3d want = Eigen::Vector3d(-hx, -hy, 1).normalized();
      EXPECT_LT((freeform_normal(x, y) - want).norm(), 1e-8);
    }
  }
}

TEST(FreeformPart, MeshIsClosedOutwardWithTheAnalyticVolume) {
  const BenchmarkPart part = make_part(PartId::kFreeform, coarse());
  expect_closed_and_consistent(part.mesh);
  // ∫∫ h: only the constant and the cos((x+y)π/50) term survive the
  // symmetric domain.
  const double k = kPi / 50;
  const double volume =
      20.0 * 60 * 40 + 1.5 * (2 * std::sin(30 * k) / k) * (2 * std::sin(20 * k) / k);
  EXPECT_NEAR(signed_volume_mm3(part.mesh), volume, 2e-3 * volume);
  std::set<int> ids(part.triangle_surface.begin(), part.triangle_surface.end());
  EXPECT_EQ(ids, (std::set<int>{1, 2, 3, 4}));
}

TEST(FreeformPart, BallCentreStaysOneRadiusFromTheSurface) {
  const BenchmarkPart part = make_part(PartId::kFreeform, coarse());
  const CanonProgram program = interpret(part);
  const double r = part.metadata.tools[0].radius_mm;
  for (const char* name : {"FREEFORM_3PLUS2", "FREEFORM_5AXIS"}) {
    int on_surface = 0, lifted = 0;
    for (const CanonCall& c : truecut::interp::moves_of_operation(program, name)) {
      const auto* end = feed_end(c);
      if (!end) continue;
      EXPECT_TRUE(c.context.tcp) << name;
      const Eigen::Vector3d centre =
          Eigen::Vector3d(end->x, end->y, end->z) + r * tool_axis(end->a, end->c);
      const double d = distance_to_freeform(centre);
      if (std::abs(d - r) < 2e-4) {
        ++on_surface;
      } else {
        EXPECT_GT(d, r + 4.0) << name << " at " << end->x << " " << end->y;
        ++lifted;
      }
    }
    EXPECT_GT(on_surface, 300) << name;
    EXPECT_LE(lifted, 1) << name;  // the retract along the tool axis
  }
}

TEST(FreeformPart, ThreePlusTwoKeepsTheTiltFixed) {
  const BenchmarkPart part = make_part(PartId::kFreeform, coarse());
  const auto moves = truecut::interp::moves_of_operation(interpret(part), "FREEFORM_3PLUS2");
  ASSERT_FALSE(moves.empty());
  for (const CanonCall& c : moves) {
    const auto& end = std::visit(
        [](const auto& op) -> truecut::interp::Axes6 {
          if constexpr (requires { op.end; }) return op.end;
          return {};
        },
        c.op);
    EXPECT_DOUBLE_EQ(end.a, 20.0);
    EXPECT_DOUBLE_EQ(end.c, 0.0);
  }
}

TEST(FreeformPart, FiveAxisMovesFollowTheNormalContinuouslyWithinTravel) {
  const BenchmarkPart part = make_part(PartId::kFreeform, coarse());
  const auto moves = truecut::interp::moves_of_operation(interpret(part), "FREEFORM_5AXIS");
  const truecut::interp::Axes6* prev = nullptr;
  double a_lo = 1e9, a_hi = -1e9, c_lo = 1e9, c_hi = -1e9, max_step = 0;
  for (const CanonCall& c : moves) {
    const auto* end = feed_end(c);
    if (!end) continue;
    EXPECT_GE(end->a, part.metadata.a_min_deg);
    EXPECT_LE(end->a, part.metadata.a_max_deg);
    // The tool axis stays within the side tilt (30°) of the surface normal.
    const Eigen::Vector3d axis = tool_axis(end->a, end->c);
    const double r = part.metadata.tools[0].radius_mm;
    const Eigen::Vector3d centre = Eigen::Vector3d(end->x, end->y, end->z) + r * axis;
    if (std::abs(distance_to_freeform(centre) - r) < 1e-3) {
      const Eigen::Vector2d f = foot_on_freeform(centre);
      const double angle_deg =
          std::acos(std::clamp(axis.dot(freeform_normal(f.x(), f.y())), -1.0, 1.0)) * 180 / kPi;
      EXPECT_NEAR(angle_deg, 30.0, 0.05);  // the side tilt
    }
    if (prev) {
      max_step = std::max({max_step, std::abs(end->a - prev->a), std::abs(end->c - prev->c)});
    }
    a_lo = std::min(a_lo, end->a);
    a_hi = std::max(a_hi, end->a);
    c_lo = std::min(c_lo, end->c);
    c_hi = std::max(c_hi, end->c);
    prev = end;
  }
  EXPECT_LT(max_step, 1.5) << "A/C jump between consecutive points";
  EXPECT_GT(a_lo, 2.0) << "too close to the A = 0 singularity";
  EXPECT_GT(a_hi - a_lo, 5.0) << "A does not follow the surface";
  EXPECT_GT(c_hi - c_lo, 5.0) << "C does not follow the surface";
}

TEST(BenchmarkParts, GenerationIsDeterministic) {
  for (PartId id : kAllParts) {
    const BenchmarkPart a = make_part(id, coarse());
    const BenchmarkPart b = make_part(id, coarse());
    EXPECT_EQ(a.program, b.program);
    EXPECT_EQ(a.mesh.vertices_mm, b.mesh.vertices_mm);
    EXPECT_EQ(a.mesh.triangles, b.mesh.triangles);
    EXPECT_EQ(part_json(a), part_json(b));
    EXPECT_EQ(format_machine_description(part_machine(a)),
              format_machine_description(part_machine(b)));
  }
}

TEST(BenchmarkParts, WritePartWritesAllFilesAndNoTemporaries) {
  const auto dir = truecut::test::scratch_dir() / "implant";
  const BenchmarkPart part = make_part(PartId::kImplant, coarse());
  write_part(part, dir);
  const auto stl = truecut::offline::read_stl(dir / "nominal.stl");
  EXPECT_EQ(stl.triangles.size(), part.mesh.triangles.size());
  EXPECT_EQ(truecut::test::read_file(dir / "program.ngc"), part.program);
  EXPECT_EQ(truecut::test::read_file(dir / "tools.tbl"), tool_table_text(part.metadata));
  const std::string json = truecut::test::read_file(dir / "part.json");
  EXPECT_NE(json.find("\"SHAFT_PERIPHERAL\""), std::string::npos);
  EXPECT_NE(json.find("\"shaft_top\""), std::string::npos);
  EXPECT_EQ(read_machine_description(dir / "machine.json"), part_machine(part));
  EXPECT_EQ(read_machine_description(dir / "machine_ideal.json"), part_machine_ideal(part));
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    EXPECT_NE(entry.path().extension(), ".tmp") << entry.path();
  }
}
