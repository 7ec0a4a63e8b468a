// The implant: a slender square shaft (1.6 mm, 17 mm cantilever) on a base
// block, as in Denkena et al.'s optical-compensation study. Face milling of
// the shaft top, then peripheral milling of the four shaft faces.
#include <array>
#include <cmath>

#include "parts/mesh_builder.hpp"
#include "parts/part_builders.hpp"
#include "parts/program_writer.hpp"

namespace truecut::sim::parts {
namespace {

constexpr double kHalfWidthMm = 0.8;  // shaft 1.6 × 1.6
constexpr double kShaftLengthMm = 17.0;
constexpr double kBaseHalfMm = 6.0;  // base 12 × 12
constexpr double kBaseHeightMm = 5.0;
constexpr double kAllowanceMm = 0.3;  // pre-roughed shaft blank, per side and on top
constexpr double kSafeZMm = 25.0;

enum Surface {
  kShaftXPos = 1,
  kShaftXNeg,
  kShaftYPos,
  kShaftYNeg,
  kShaftTop,
  kBaseTop,
  kBaseSides,
  kBaseBottom
};

void build_mesh(MeshBuilder& b, double edge_mm) {
  const double w = kHalfWidthMm, s = kBaseHalfMm, h = kShaftLengthMm, d = kBaseHeightMm;
  const auto shaft_xy = lines(-w, w, edge_mm);
  // Base grid lines include the shaft outline so the base top meets the shaft.
  const auto base_xy = join({lines(-s, -w, edge_mm), shaft_xy, lines(w, s, edge_mm)});
  const auto shaft_z = lines(0, h, edge_mm);
  const auto base_z = lines(-d, 0, edge_mm);
  using V = Eigen::Vector3d;

  b.patch(
      base_xy, base_xy, [&](double x, double y) { return V(x, y, -d); }, true, kBaseBottom);
  b.patch(
      base_xy, base_xy, [&](double x, double y) { return V(x, y, 0); }, false, kBaseTop,
      [&](double x, double y) { return std::abs(x) < w && std::abs(y) < w; });
  b.patch(
      base_xy, base_z, [&](double y, double z) { return V(s, y, z); }, false, kBaseSides);
  b.patch(
      base_xy, base_z, [&](double y, double z) { return V(-s, y, z); }, true, kBaseSides);
  b.patch(
      base_xy, base_z, [&](double x, double z) { return V(x, s, z); }, true, kBaseSides);
  b.patch(
      base_xy, base_z, [&](double x, double z) { return V(x, -s, z); }, false, kBaseSides);

  b.patch(
      shaft_xy, shaft_z, [&](double y, double z) { return V(w, y, z); }, false, kShaftXPos);
  b.patch(
      shaft_xy, shaft_z, [&](double y, double z) { return V(-w, y, z); }, true, kShaftXNeg);
  b.patch(
      shaft_xy, shaft_z, [&](double x, double z) { return V(x, w, z); }, true, kShaftYPos);
  b.patch(
      shaft_xy, shaft_z, [&](double x, double z) { return V(x, -w, z); }, false, kShaftYNeg);
  b.patch(
      shaft_xy, shaft_xy, [&](double x, double y) { return V(x, y, h); }, false, kShaftTop);
}

PartMetadata metadata() {
  PartMetadata m;
  m.name = "implant";
  m.frame =
      "workpiece frame: origin at the centre of the base top face, +Z along the shaft axis, "
      "shaft faces normal to ±X and ±Y";
  m.material = "Ti-6Al-4V";
  m.stock = {
      {{-kBaseHalfMm, -kBaseHalfMm, -kBaseHeightMm}, {kBaseHalfMm, kBaseHalfMm, 0}},
      {{-kHalfWidthMm - kAllowanceMm, -kHalfWidthMm - kAllowanceMm, 0},
       {kHalfWidthMm + kAllowanceMm, kHalfWidthMm + kAllowanceMm, kShaftLengthMm + kAllowanceMm}}};
  m.tools = {{1, "flat_end_mill", 1.0, 0.0, 35.0, 20.0, 3, "flat end mill D2 carbide, long reach"},
             {2, "flat_end_mill", 2.0, 0.0, 40.0, 8.0, 4, "flat end mill D4 carbide"}};
  m.surfaces = {
      {kShaftXPos, "shaft_x_pos", "plane", true}, {kShaftXNeg, "shaft_x_neg", "plane", true},
      {kShaftYPos, "shaft_y_pos", "plane", true}, {kShaftYNeg, "shaft_y_neg", "plane", true},
      {kShaftTop, "shaft_top", "plane", true},    {kBaseTop, "base_top", "plane", false},
      {kBaseSides, "base_sides", "plane", false}, {kBaseBottom, "base_bottom", "plane", false}};
  m.operations = {
      {"SHAFT_TOP_FACE", 2, "face", {kShaftTop}},
      {"SHAFT_PERIPHERAL", 1, "peripheral", {kShaftXPos, kShaftXNeg, kShaftYPos, kShaftYNeg}}};
  m.a_min_deg = 0;  // 3-axis part: A and C stay at zero
  m.a_max_deg = 0;
  return m;
}

void face_top(ProgramWriter& w, const PartTool& tool, const PartOptions& o) {
  w.operation("SHAFT_TOP_FACE");
  change_tool(w, tool, 12000);
  const double x_out = kHalfWidthMm + tool.radius_mm + 0.5;
  const auto ys = lines(-kHalfWidthMm, kHalfWidthMm, o.stepover_mm);
  const double z = kShaftLengthMm;
  w.move("G0", {-x_out, ys.front(), kSafeZMm});
  w.move("G0", {-x_out, ys.front(), z + 2});
  w.move("G1", {-x_out, ys.front(), z}, 200);
  w.line("F600");
  for (std::size_t i = 0; i < ys.size(); ++i) {
    const double x_end = (i % 2 == 0) ? x_out : -x_out;  // zig-zag
    if (i > 0) w.move("G1", {-x_end, ys[i], z});
    w.move("G1", {x_end, ys[i], z});
  }
  w.move("G0", {(ys.size() % 2 == 1) ? x_out : -x_out, ys.back(), kSafeZMm});
}

// Climb milling around the outside of the square: clockwise seen from +Z
// with the spindle turning clockwise; tangential lead in and out along +X.
void peripheral(ProgramWriter& w, const PartTool& tool, const PartOptions& o) {
  w.operation("SHAFT_PERIPHERAL");
  change_tool(w, tool, 18000);
  const double a = kHalfWidthMm, r = tool.radius_mm, c = a + r;
  const double lead = 2.0 + r + kAllowanceMm;
  // Levels from the top down to the base top face; the flank cuts the wall.
  std::vector<double> zs;
  for (int k = 1;; ++k) {
    const double z = kShaftLengthMm - k * o.step_down_mm;
    if (z <= 1e-9) break;
    zs.push_back(z);
  }
  zs.push_back(0.0);
  for (double z : zs) {
    w.move("G0", {-a - lead, c, kSafeZMm});
    w.move("G0", {-a - lead, c, z + 1});
    w.move("G1", {-a - lead, c, z}, 300);
    w.line("F500");
    w.move("G1", {a, c, z});
    w.line("G2 X" + number(c) + " Y" + number(a) + " I0 J" + number(-r));
    w.move("G1", {c, -a, z});
    w.line("G2 X" + number(a) + " Y" + number(-c) + " I" + number(-r) + " J0");
    w.move("G1", {-a, -c, z});
    w.line("G2 X" + number(-c) + " Y" + number(-a) + " I0 J" + number(r));
    w.move("G1", {-c, a, z});
    w.line("G2 X" + number(-a) + " Y" + number(c) + " I" + number(r) + " J0");
    w.move("G1", {a + lead, c, z});  // lead out past the start of the contour
    w.move("G0", {a + lead, c, kSafeZMm});
  }
}

}  // namespace

BenchmarkPart make_implant(const PartOptions& options) {
  BenchmarkPart part;
  part.id = PartId::kImplant;
  part.options = options;
  part.metadata = metadata();
  MeshBuilder b;
  build_mesh(b, options.mesh_edge_mm);
  part.mesh = std::move(b.mesh);
  part.triangle_surface = std::move(b.triangle_surface);

  ProgramWriter w;
  start_program(w, part.metadata);
  face_top(w, part.metadata.tools[1], options);
  peripheral(w, part.metadata.tools[0], options);
  end_program(w);
  part.program = w.text();
  return part;
}

}  // namespace truecut::sim::parts
