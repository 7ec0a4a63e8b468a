// The free-form part: a warped height field over 60 × 40 mm on a block,
// finished with a Ø6 ball end mill — the south half (y ≤ 0) in 3+2 with a
// fixed tilt, the north half (y ≥ 0) in continuous 5-axis with TRAORI.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "parts/mesh_builder.hpp"
#include "parts/part_builders.hpp"
#include "parts/program_writer.hpp"

namespace truecut::sim {

double freeform_height_mm(double x, double y) {
  constexpr double pi = std::numbers::pi;
  // Saddle-like warp plus a twist: slopes up to ~20°, curvature radii > 25 mm.
  return 20.0 + 3.0 * std::sin(pi * x / 30.0) * std::cos(pi * y / 40.0) + 0.003 * x * y +
         1.5 * std::cos(pi * (x + y) / 50.0);
}

Eigen::Vector3d freeform_normal(double x, double y) {
  constexpr double pi = std::numbers::pi;
  const double s = std::sin(pi * (x + y) / 50.0) * 1.5 * pi / 50.0;
  const double hx =
      3.0 * pi / 30.0 * std::cos(pi * x / 30.0) * std::cos(pi * y / 40.0) + 0.003 * y - s;
  const double hy =
      -3.0 * pi / 40.0 * std::sin(pi * x / 30.0) * std::sin(pi * y / 40.0) + 0.003 * x - s;
  return Eigen::Vector3d(-hx, -hy, 1.0).normalized();
}

namespace parts {
namespace {

constexpr double kHalfXMm = 30.0;
constexpr double kHalfYMm = 20.0;
constexpr double kSafeZMm = 50.0;
constexpr double kTilt32Deg = 20.0;    // fixed A of the 3+2 operation (C = 0)
constexpr double kSideTiltDeg = 30.0;  // 5-axis: tool axis = normal tilted towards +Y
// Largest A or C change between consecutive points; longer steps are split.
constexpr double kMaxRotaryStepDeg = 1.0;
constexpr double kFeed = 1500.0, kPlungeFeed = 400.0;

enum Surface { kTopSouth = 1, kTopNorth, kSides, kBottom };

void build_mesh(MeshBuilder& b, double edge_mm) {
  const auto xs = lines(-kHalfXMm, kHalfXMm, edge_mm);
  const auto ys = join({lines(-kHalfYMm, 0, edge_mm), lines(0, kHalfYMm, edge_mm)});
  const double max_h = 26.0;  // above the largest height
  const auto ts = lines(0, 1, edge_mm / max_h);
  using V = Eigen::Vector3d;
  const auto top = [](double x, double y) { return V(x, y, freeform_height_mm(x, y)); };
  b.patch(xs, ys, top, false, kTopSouth, [](double, double y) { return y > 0; });
  b.patch(xs, ys, top, false, kTopNorth, [](double, double y) { return y < 0; });
  b.patch(
      xs, ys, [](double x, double y) { return V(x, y, 0); }, true, kBottom);
  const auto wall_x = [](double x) {
    return [x](double y, double t) { return V(x, y, t * freeform_height_mm(x, y)); };
  };
  const auto wall_y = [](double y) {
    return [y](double x, double t) { return V(x, y, t * freeform_height_mm(x, y)); };
  };
  b.patch(ys, ts, wall_x(kHalfXMm), false, kSides);
  b.patch(ys, ts, wall_x(-kHalfXMm), true, kSides);
  b.patch(xs, ts, wall_y(kHalfYMm), true, kSides);
  b.patch(xs, ts, wall_y(-kHalfYMm), false, kSides);
}

PartMetadata metadata() {
  PartMetadata m;
  m.name = "freeform";
  m.frame =
      "workpiece frame: origin at the centre of the bottom face, +Z up; the free-form top spans "
      "x in [-30, 30], y in [-20, 20]";
  m.material = "AlZnMgCu1.5 (7075)";
  m.stock = {{{-kHalfXMm, -kHalfYMm, 0}, {kHalfXMm, kHalfYMm, 27.0}}};
  m.tools = {{1, "ball_end_mill", 3.0, 3.0, 60.0, 15.0, 2, "ball end mill D6 carbide"}};
  m.surfaces = {{kTopSouth, "freeform_top_south", "freeform", true},
                {kTopNorth, "freeform_top_north", "freeform", true},
                {kSides, "sides", "freeform", false},
                {kBottom, "bottom", "plane", false}};
  m.operations = {{"FREEFORM_3PLUS2", 1, "3+2", {kTopSouth}},
                  {"FREEFORM_5AXIS", 1, "5-axis", {kTopNorth}}};
  m.a_min_deg = -10.0;
  m.a_max_deg = 110.0;
  return m;
}

constexpr double deg(double rad) {
  return rad * 180.0 / std::numbers::pi;
}
constexpr double rad(double deg) {
  return deg * std::numbers::pi / 180.0;
}

// docs/kinematics.md (σ = +1): axis = (sin A sin C, sin A cos C, cos A).
struct Orientation {
  double a_deg, c_deg;
};
Orientation orientation_of(const Eigen::Vector3d& axis) {
  return {deg(std::acos(std::clamp(axis.z(), -1.0, 1.0))), deg(std::atan2(axis.x(), axis.y()))};
}

// The surface normal turned by exactly kSideTiltDeg towards +Y (in the plane
// of the normal and +Y): the ball never cuts with its tip, where the cutting
// speed is zero, and A stays clear of the A = 0 singularity.
Eigen::Vector3d five_axis_axis(double x, double y) {
  const Eigen::Vector3d n = freeform_normal(x, y);
  const Eigen::Vector3d side = (Eigen::Vector3d::UnitY() - n.y() * n).normalized();
  return std::cos(rad(kSideTiltDeg)) * n + std::sin(rad(kSideTiltDeg)) * side;
}

// Ball centre offset by R along the surface normal; the tip is R back along
// the tool axis from the centre.
Eigen::Vector3d tip_of(double x, double y, const Eigen::Vector3d& axis, double r) {
  const Eigen::Vector3d centre =
      Eigen::Vector3d(x, y, freeform_height_mm(x, y)) + r * freeform_normal(x, y);
  return centre - r * axis;
}

// Zig-zag passes along X over y ∈ [y0, y1]; `axis_at` gives the tool axis.
template <class AxisAt>
void raster(ProgramWriter& w, double y0, double y1, double r, const PartOptions& o,
            const AxisAt& axis_at) {
  const auto xs = lines(-kHalfXMm, kHalfXMm, o.point_spacing_mm);
  const auto ys = lines(y0, y1, o.stepover_mm);
  const auto emit = [&](std::string_view g, double x, double y, std::optional<double> f,
                        double lift_mm) {
    const Eigen::Vector3d axis = axis_at(x, y);
    const Orientation ori = orientation_of(axis);
    w.move5(g, tip_of(x, y, axis, r) + lift_mm * axis, ori.a_deg, ori.c_deg, f);
  };
  const Eigen::Vector3d first_axis = axis_at(xs.front(), ys.front());
  const Orientation first = orientation_of(first_axis);
  const Eigen::Vector3d first_tip = tip_of(xs.front(), ys.front(), first_axis, r);
  w.move5("G0", {first_tip.x(), first_tip.y(), kSafeZMm}, first.a_deg, first.c_deg);
  emit("G0", xs.front(), ys.front(), {}, 5.0);
  emit("G1", xs.front(), ys.front(), kPlungeFeed, 0.0);
  w.line("F" + number(kFeed, 0));
  // Contact points from (x0, y0) to (x1, y1), excluding the start, split so
  // that neither A nor C moves more than kMaxRotaryStepDeg between points.
  const auto segment = [&](double x0, double y0, double x1, double y1) {
    const Orientation o0 = orientation_of(axis_at(x0, y0));
    const Orientation o1 = orientation_of(axis_at(x1, y1));
    const double turn = std::max(std::abs(o1.a_deg - o0.a_deg), std::abs(o1.c_deg - o0.c_deg));
    const int n = std::max(1, static_cast<int>(std::ceil(turn / kMaxRotaryStepDeg)));
    for (int i = 1; i <= n; ++i) {
      const double t = static_cast<double>(i) / n;
      emit("G1", x0 + t * (x1 - x0), y0 + t * (y1 - y0), {}, 0.0);
    }
  };
  double x_prev = xs.front(), y_prev = ys.front();
  for (std::size_t j = 0; j < ys.size(); ++j) {
    for (std::size_t k = 0; k < xs.size(); ++k) {
      const double x = (j % 2 == 0) ? xs[k] : xs[xs.size() - 1 - k];
      if (j == 0 && k == 0) continue;
      segment(x_prev, y_prev, x, ys[j]);
      x_prev = x;
      y_prev = ys[j];
    }
  }
  const double x_last = (ys.size() % 2 == 1) ? xs.back() : xs.front();
  emit("G1", x_last, ys.back(), {}, 5.0);  // retract along the tool axis
  const Eigen::Vector3d lifted = tip_of(x_last, ys.back(), axis_at(x_last, ys.back()), r);
  const Orientation last = orientation_of(axis_at(x_last, ys.back()));
  w.move5("G0", {lifted.x(), lifted.y(), kSafeZMm}, last.a_deg, last.c_deg);
}

}  // namespace

BenchmarkPart make_freeform(const PartOptions& options) {
  BenchmarkPart part;
  part.id = PartId::kFreeform;
  part.options = options;
  part.metadata = metadata();
  MeshBuilder b;
  build_mesh(b, options.mesh_edge_mm);
  part.mesh = std::move(b.mesh);
  part.triangle_surface = std::move(b.triangle_surface);

  const PartTool& ball = part.metadata.tools[0];
  ProgramWriter w;
  start_program(w, part.metadata);
  w.operation("FREEFORM_3PLUS2");
  change_tool(w, ball, 12000);
  w.line("TRAORI");
  const Eigen::Vector3d tilted(0, std::sin(rad(kTilt32Deg)), std::cos(rad(kTilt32Deg)));
  raster(w, -kHalfYMm, 0.0, ball.radius_mm, options, [&](double, double) { return tilted; });
  w.operation("FREEFORM_5AXIS");
  raster(w, 0.0, kHalfYMm, ball.radius_mm, options, five_axis_axis);
  w.move5("G0", {0, 0, kSafeZMm}, 0, 0);
  w.line("TRAFOOF");
  end_program(w);
  part.program = w.text();
  return part;
}

}  // namespace parts
}  // namespace truecut::sim
