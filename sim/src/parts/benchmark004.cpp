// benchmark004: a Ø100 × 55 mm stepped cylinder with a hemisphere on top,
// after the benchmark part of Sortino et al.'s 3D model adaptation study.
// Finished with a flat end mill (walls by peripheral milling, step faces by
// face milling) and a ball end mill (hemisphere: 3-axis waterline rings, the
// cap around the pole as a continuous 5-axis spiral with the tool tilted, so
// the ball never cuts with its tip).
#include <algorithm>
#include <cmath>
#include <numbers>

#include "parts/mesh_builder.hpp"
#include "parts/part_builders.hpp"
#include "parts/program_writer.hpp"
#include "parts/revolved_mesh.hpp"
#include "parts/revolved_stock.hpp"
#include "truecut/sim/drive_surface.hpp"

namespace truecut::sim::parts {
namespace {

// Profile (workpiece frame: origin at the centre of the bottom face, +Z up).
constexpr double kBaseRadiusMm = 50.0;  // z ∈ [0, 15]
constexpr double kStep1ZMm = 15.0;
constexpr double kStepRadiusMm = 40.0;  // z ∈ [15, 30]
constexpr double kStep2ZMm = 30.0;
constexpr double kCollarRadiusMm = 20.0;  // z ∈ [30, 35]
constexpr double kSphereCentreZMm = 35.0;
constexpr double kSphereRadiusMm = 20.0;  // top at z = 55
// The cap (polar angle ≤ kCapDeg) is machined in 5-axis, the rest in 3-axis.
constexpr double kCapDeg = 30.0;
// 5-axis: the tool axis leans kTiltDeg further from the pole than the normal.
constexpr double kTiltDeg = 20.0;
// Stock: at least kAllowanceMm on every machined surface; box corners at
// most kMaxAllowanceMm (kMaxDomeAllowanceMm on the hemisphere) away.
constexpr double kAllowanceMm = 0.5;
constexpr double kMaxAllowanceMm = 1.0;
constexpr double kMaxDomeAllowanceMm = 1.5;

constexpr double kSafeZMm = 70.0;
constexpr double kLeadMm = 12.0;  // tangential lead in/out, clear of the stock
constexpr double kMaxRotaryStepDeg = 1.0;
constexpr double kEndMillRpm = 9500, kBallRpm = 12000;
constexpr double kWallFeed = 1000, kFaceFeed = 1200, kBallFeed = 1200, kPlungeFeed = 300;

enum Surface {
  kHemisphere = 1,
  kHemisphereCap,
  kCollarWall,
  kStep2Face,
  kStep1Wall,
  kStep1Face,
  kCylinderWall,
  kBottom
};

constexpr double rad(double deg) {
  return deg * std::numbers::pi / 180.0;
}
constexpr double deg(double rad) {
  return rad * 180.0 / std::numbers::pi;
}

void build_mesh(MeshBuilder& b, double edge_mm) {
  std::vector<ProfilePoint> profile;
  std::vector<int> surface;
  // Straight profile runs split into pieces of at most edge_mm.
  const auto run = [&](ProfilePoint to, int id) {
    const ProfilePoint from = profile.back();
    const double len = std::hypot(to.rho_mm - from.rho_mm, to.z_mm - from.z_mm);
    const auto ts = lines(0, 1, edge_mm / len);
    for (std::size_t k = 1; k < ts.size(); ++k) {
      profile.push_back(k + 1 == ts.size()
                            ? to
                            : ProfilePoint{from.rho_mm + ts[k] * (to.rho_mm - from.rho_mm),
                                           from.z_mm + ts[k] * (to.z_mm - from.z_mm)});
      surface.push_back(id);
    }
  };
  profile.push_back({0, 0});
  run({kBaseRadiusMm, 0}, kBottom);
  run({kBaseRadiusMm, kStep1ZMm}, kCylinderWall);
  run({kStepRadiusMm, kStep1ZMm}, kStep1Face);
  run({kStepRadiusMm, kStep2ZMm}, kStep1Wall);
  run({kCollarRadiusMm, kStep2ZMm}, kStep2Face);
  run({kCollarRadiusMm, kSphereCentreZMm}, kCollarWall);
  // Meridian from the equator to the pole, with a ring exactly at the cap edge.
  const double r = kSphereRadiusMm;
  const auto band = lines(90.0, kCapDeg, deg(edge_mm / r));
  const auto cap = lines(kCapDeg, 0.0, deg(edge_mm / r));
  const auto polar = join({band, cap});
  for (std::size_t k = 1; k < polar.size(); ++k) {
    const double phi = rad(polar[k]);
    profile.push_back(k + 1 == polar.size()
                          ? ProfilePoint{0, kSphereCentreZMm + r}
                          : ProfilePoint{r * std::sin(phi), kSphereCentreZMm + r * std::cos(phi)});
    surface.push_back(polar[k] >= kCapDeg ? kHemisphere : kHemisphereCap);
  }
  revolve(b, profile, surface, edge_mm);
}

std::vector<StockBox> stock() {
  // Corners of a cylinder slice sit at most kMaxAllowanceMm from the step
  // edge above it: ρ_out = R + √(max² − min²).
  const double band = std::sqrt(kMaxAllowanceMm * kMaxAllowanceMm - kAllowanceMm * kAllowanceMm);
  std::vector<StockBox> boxes;
  add_disc_boxes(boxes, kBaseRadiusMm + kAllowanceMm, kBaseRadiusMm + band, 0,
                 kStep1ZMm + kAllowanceMm);
  add_disc_boxes(boxes, kStepRadiusMm + kAllowanceMm, kStepRadiusMm + band,
                 kStep1ZMm + kAllowanceMm, kStep2ZMm + kAllowanceMm);
  add_disc_boxes(boxes, kCollarRadiusMm + kAllowanceMm, kCollarRadiusMm + band,
                 kStep2ZMm + kAllowanceMm, kSphereCentreZMm);
  add_dome_boxes(boxes, kSphereRadiusMm + kAllowanceMm, kSphereRadiusMm + kMaxDomeAllowanceMm,
                 kSphereCentreZMm);
  return boxes;
}

PartMetadata metadata() {
  PartMetadata m;
  m.name = "benchmark004";
  m.frame =
      "workpiece frame: origin at the centre of the bottom face, +Z along the cylinder axis; "
      "hemisphere R20 centred at z = 35, top at z = 55";
  m.material = "AlMgSi1 (6082-T6)";
  m.stock = stock();
  m.tools = {{1, "flat_end_mill", 5.0, 0.0, 60.0, 22.0, 3, "flat end mill D10 carbide"},
             {2, "ball_end_mill", 3.0, 3.0, 50.0, 12.0, 2, "ball end mill D6 carbide"}};
  m.surfaces = {{kHemisphere, "hemisphere", "sphere", true},
                {kHemisphereCap, "hemisphere_cap", "sphere", true},
                {kCollarWall, "collar_wall", "cylinder", true},
                {kStep2Face, "step2_face", "plane", true},
                {kStep1Wall, "step1_wall", "cylinder", true},
                {kStep1Face, "step1_face", "plane", true},
                {kCylinderWall, "cylinder_wall", "cylinder", true},
                {kBottom, "bottom", "plane", false}};
  m.operations = {{"WALLS", 1, "peripheral", {kCollarWall, kStep1Wall, kCylinderWall}},
                  {"STEP_FACES", 1, "face", {kStep2Face, kStep1Face}},
                  {"HEMISPHERE_3AXIS", 2, "3-axis", {kHemisphere}},
                  {"HEMISPHERE_CAP_5AXIS", 2, "5-axis", {kHemisphereCap}}};
  m.a_min_deg = -10.0;
  m.a_max_deg = 110.0;
  return m;
}

// Full clockwise circle about the Z axis through (x, 0, z): climb milling
// outside with the spindle turning clockwise.
void circle(ProgramWriter& w, double x, double z) {
  w.line("G2 X" + number(x) + " Y0 Z" + number(z) + " I" + number(-x) + " J0");
}

// A pass driven by the adapted geometry (DriveSurface): the offset of the
// surface the tool cuts varies around the part, so a circle becomes G1 moves
// at most point_spacing_mm apart. Angles of a clockwise turn from ψ = 0:
// 0, −2π/n, …, −2π (the last point is the first).
std::vector<double> clockwise_turn_rad(double radius_mm, double point_spacing_mm) {
  const int n = std::max(
      8, static_cast<int>(std::ceil(2 * std::numbers::pi * radius_mm / point_spacing_mm - 1e-9)));
  std::vector<double> psi(n + 1);
  for (int k = 0; k <= n; ++k)
    psi[k] = -2 * std::numbers::pi * k / n;
  return psi;
}

// The drive surface's offset at a nominal point (0 without a drive surface).
double drive_offset_mm(const DriveSurface* drive, const Eigen::Vector3d& p_mm,
                       const Eigen::Vector3d& n) {
  return drive ? drive->offset_mm(p_mm, n) : 0.0;
}

// Peripheral milling of the three walls, top down, each in levels of at most
// step_down_mm down to the face below it; tangential lead in along −Y at
// y = +kLeadMm, lead out to y = −kLeadMm. Driven by an adapted geometry, a
// level's flank sits at the mean offset of the adapted wall over the band
// [z, level above] that this level is the first to reach.
void walls(ProgramWriter& w, const PartTool& tool, const PartOptions& o,
           const DriveSurface* drive) {
  w.operation("WALLS");
  change_tool(w, tool, kEndMillRpm);
  struct Wall {
    double radius, top, bottom;
  };
  for (const Wall& wall :
       {Wall{kCollarRadiusMm, kSphereCentreZMm, kStep2ZMm},
        Wall{kStepRadiusMm, kStep2ZMm, kStep1ZMm}, Wall{kBaseRadiusMm, kStep1ZMm, 0.0}}) {
    const double rc = wall.radius + tool.radius_mm;
    std::vector<double> zs;
    for (int k = 1;; ++k) {
      const double z = wall.top - k * o.step_down_mm;
      if (z <= wall.bottom + 1e-9) break;
      zs.push_back(z);
    }
    zs.push_back(wall.bottom);
    double band_top = wall.top;
    for (double z : zs) {
      std::vector<Eigen::Vector3d> turn;  // driven: the pass's points, ψ = 0 first
      if (drive) {
        const auto psis = clockwise_turn_rad(rc, o.point_spacing_mm);
        for (std::size_t k = 0; k + 1 < psis.size(); ++k) {
          const Eigen::Vector3d n(std::cos(psis[k]), std::sin(psis[k]), 0);
          double sum = 0;
          for (double f : {1.0 / 6, 0.5, 5.0 / 6}) {
            const Eigen::Vector3d p =
                wall.radius * n + Eigen::Vector3d(0, 0, z + f * (band_top - z));
            sum += drive_offset_mm(drive, p, n);
          }
          turn.push_back((rc + sum / 3) * n + Eigen::Vector3d(0, 0, z));
        }
      }
      const double x0 = drive ? turn.front().x() : rc;
      w.move("G0", {x0, kLeadMm, kSafeZMm});
      w.move("G0", {x0, kLeadMm, z + 1});
      w.move("G1", {x0, kLeadMm, z}, kPlungeFeed);
      w.move("G1", {x0, 0, z}, kWallFeed);
      if (drive) {
        for (std::size_t k = 1; k < turn.size(); ++k)
          w.move("G1", turn[k]);
        w.move("G1", turn.front());
      } else {
        circle(w, rc, z);
      }
      w.move("G1", {x0, -kLeadMm, z});
      w.move("G0", {x0, -kLeadMm, kSafeZMm});
      band_top = z;
    }
  }
}

// Face milling of the two step faces: concentric clockwise circles from the
// outside in, the first reached by one helical turn down from 1.5 mm above.
// Driven by an adapted geometry, the tool's bottom sits at the mean offset of
// the adapted face under it (its centre and eight points at 0.6 r, those on
// the face at least kFaceMarginMm inside its edges).
void step_faces(ProgramWriter& w, const PartTool& tool, const PartOptions& o,
                const DriveSurface* drive) {
  w.operation("STEP_FACES");
  const double r = tool.radius_mm;
  constexpr double kFaceMarginMm = 0.3;
  struct Face {
    double z, rc_outer, rc_inner, rho_min, rho_max;
  };
  const auto tip = [&](const Face& f, double rho_c, double psi) {
    const Eigen::Vector2d c = rho_c * Eigen::Vector2d(std::cos(psi), std::sin(psi));
    double sum = 0;
    int n = 0;
    for (int k = -1; k < 8 && drive; ++k) {
      const double a = 2 * std::numbers::pi * k / 8;
      const Eigen::Vector2d q =
          k < 0 ? c : Eigen::Vector2d(c + 0.6 * r * Eigen::Vector2d(std::cos(a), std::sin(a)));
      if (q.norm() < f.rho_min + kFaceMarginMm || q.norm() > f.rho_max - kFaceMarginMm) continue;
      sum += drive_offset_mm(drive, {q.x(), q.y(), f.z}, Eigen::Vector3d::UnitZ());
      ++n;
    }
    return Eigen::Vector3d(c.x(), c.y(), f.z + (n > 0 ? sum / n : 0.0));
  };
  // Step 2: between the collar (flank at ρ = 20) and the step-1 wall (40).
  // Step 1: from the step-1 wall (flank at 40) past the open outer edge.
  for (const Face& f :
       {Face{kStep2ZMm, kStepRadiusMm - r, kCollarRadiusMm + r, kCollarRadiusMm, kStepRadiusMm},
        Face{kStep1ZMm, kBaseRadiusMm, kStepRadiusMm + r, kStepRadiusMm, kBaseRadiusMm}}) {
    const auto radii = lines(f.rc_outer, f.rc_inner, o.stepover_mm);
    const Eigen::Vector3d first = tip(f, radii.front(), 0);
    w.move("G0", {radii.front(), 0, kSafeZMm});
    w.move("G0", {radii.front(), 0, f.z + 1.5});
    w.line("G2 X" + number(radii.front()) + " Y0 Z" + number(first.z()) + " I" +
           number(-radii.front()) + " J0 F" + number(kPlungeFeed, 0));
    w.line("F" + number(kFaceFeed, 0));
    for (std::size_t k = 0; k < radii.size(); ++k) {
      if (!drive) {
        if (k > 0) w.move("G1", {radii[k], 0, f.z});
        circle(w, radii[k], f.z);
        continue;
      }
      const auto psis = clockwise_turn_rad(radii[k], o.point_spacing_mm);
      const Eigen::Vector3d start = tip(f, radii[k], 0);
      if (k > 0) w.move("G1", start);
      for (std::size_t i = 1; i + 1 < psis.size(); ++i)
        w.move("G1", tip(f, radii[k], psis[i]));
      w.move("G1", start);
    }
    w.move("G0", {radii.back(), 0, kSafeZMm});
  }
}

Eigen::Vector3d unit(double phi_rad, double psi_rad) {
  return {std::sin(phi_rad) * std::cos(psi_rad), std::sin(phi_rad) * std::sin(psi_rad),
          std::cos(phi_rad)};
}

// Ball end mill, 3-axis: one clockwise ring per polar angle from the equator
// up to the cap edge; the ball centre runs on the sphere of radius R + r_b
// (driven by an adapted geometry: R + offset + r_b along the normal of the
// contact point). Between rings the tool climbs along the meridian at ψ = 0
// in steps of at most point_spacing_mm.
void hemisphere_3axis(ProgramWriter& w, const PartTool& ball, const PartOptions& o,
                      const DriveSurface* drive) {
  w.operation("HEMISPHERE_3AXIS");
  change_tool(w, ball, kBallRpm);
  const double rb = ball.radius_mm, rc = kSphereRadiusMm + rb;
  const Eigen::Vector3d centre(0, 0, kSphereCentreZMm);
  const auto tip = [&](double phi_deg, double psi_rad) {
    const Eigen::Vector3d u = unit(rad(phi_deg), psi_rad);
    const double d = drive_offset_mm(drive, centre + kSphereRadiusMm * u, u);
    return Eigen::Vector3d(centre + (rc + d) * u - Eigen::Vector3d(0, 0, rb));
  };
  const auto phis = lines(90.0, kCapDeg, deg(o.stepover_mm / kSphereRadiusMm));
  const Eigen::Vector3d start = tip(phis.front(), 0);
  w.move("G0", {start.x(), kLeadMm, kSafeZMm});
  w.move("G0", {start.x(), kLeadMm, start.z() + 1});
  w.move("G1", {start.x(), kLeadMm, start.z()}, kPlungeFeed);
  w.move("G1", start, kBallFeed);
  for (std::size_t k = 0; k < phis.size(); ++k) {
    if (k > 0) {
      const auto steps = lines(phis[k - 1], phis[k], deg(o.point_spacing_mm / rc));
      for (std::size_t i = 1; i < steps.size(); ++i)
        w.move("G1", tip(steps[i], 0));
    }
    const Eigen::Vector3d p = tip(phis[k], 0);
    if (!drive) {
      circle(w, p.x(), p.z());
      continue;
    }
    const auto psis = clockwise_turn_rad(p.x(), o.point_spacing_mm);
    for (std::size_t i = 1; i + 1 < psis.size(); ++i)
      w.move("G1", tip(phis[k], psis[i]));
    w.move("G1", p);
  }
  const Eigen::Vector3d end = tip(phis.back(), 0);
  w.move("G1", {end.x(), -kLeadMm, end.z()});
  w.move("G0", {end.x(), -kLeadMm, kSafeZMm});
}

// Ball end mill, continuous 5-axis under TRAORI: a clockwise spiral of the
// contact point from the cap edge to the pole, one turn per stepover; the
// tool axis lies in the meridian plane, kTiltDeg further from the pole than
// the surface normal (A = φ + τ, C = 90° − ψ, turning on continuously).
void hemisphere_cap_5axis(ProgramWriter& w, const PartTool& ball, const PartOptions& o,
                          const DriveSurface* drive) {
  w.operation("HEMISPHERE_CAP_5AXIS");
  w.line("TRAORI");
  const double rb = ball.radius_mm, r = kSphereRadiusMm;
  const int turns =
      std::max(1, static_cast<int>(std::ceil(r * rad(kCapDeg) / o.stepover_mm - 1e-9)));
  const double path_mm = 2 * std::numbers::pi * turns * r * std::sin(rad(kCapDeg));
  const int points = std::max(static_cast<int>(std::ceil(360.0 * turns / kMaxRotaryStepDeg)),
                              static_cast<int>(std::ceil(path_mm / o.point_spacing_mm)));
  struct Pose {
    Eigen::Vector3d tip, axis;
    double a_deg, c_deg;
  };
  const auto pose = [&](int i) {
    const double t = static_cast<double>(i) / points;
    const double phi = rad(kCapDeg) * (1 - t);
    const double psi = -2 * std::numbers::pi * turns * t;
    Pose p;
    p.axis = unit(phi + rad(kTiltDeg), psi);
    const Eigen::Vector3d u = unit(phi, psi), sphere_centre(0, 0, kSphereCentreZMm);
    const double d = drive_offset_mm(drive, sphere_centre + r * u, u);
    const Eigen::Vector3d centre = sphere_centre + (r + rb + d) * u;
    p.tip = centre - rb * p.axis;
    p.a_deg = deg(phi) + kTiltDeg;
    p.c_deg = 90.0 - deg(psi);
    return p;
  };
  const Pose first = pose(0);
  w.move5("G0", {first.tip.x(), first.tip.y(), kSafeZMm}, first.a_deg, first.c_deg);
  w.move5("G0", first.tip + 5.0 * first.axis, first.a_deg, first.c_deg);
  w.move5("G1", first.tip, first.a_deg, first.c_deg, kPlungeFeed);
  w.line("F" + number(kBallFeed, 0));
  for (int i = 1; i <= points; ++i) {
    const Pose p = pose(i);
    w.move5("G1", p.tip, p.a_deg, p.c_deg);
  }
  const Pose last = pose(points);
  w.move5("G1", last.tip + 5.0 * last.axis, last.a_deg, last.c_deg);  // retract along the axis
  w.move5("G0", {last.tip.x(), last.tip.y(), kSafeZMm}, last.a_deg, last.c_deg);
  // Upright again without unwinding C: the nearest whole turn.
  w.move5("G0", {0, 0, kSafeZMm}, 0, 360.0 * std::round(last.c_deg / 360.0));
  w.line("TRAFOOF");
}

}  // namespace

BenchmarkPart make_benchmark004(const PartOptions& options, const DriveSurface* drive) {
  BenchmarkPart part;
  part.id = PartId::kBenchmark004;
  part.options = options;
  part.metadata = metadata();
  MeshBuilder b;
  build_mesh(b, options.mesh_edge_mm);
  part.mesh = std::move(b.mesh);
  part.triangle_surface = std::move(b.triangle_surface);

  ProgramWriter w;
  start_program(w, part.metadata);
  if (drive)
    w.comment(
        "tool path driven by an adapted geometry: every finishing pass placed on the adapted "
        "surface, circles as G1 moves; docs/parts.md");
  walls(w, part.metadata.tools[0], options, drive);
  step_faces(w, part.metadata.tools[0], options, drive);
  hemisphere_3axis(w, part.metadata.tools[1], options, drive);
  hemisphere_cap_5axis(w, part.metadata.tools[1], options, drive);
  end_program(w);
  part.program = w.text();
  return part;
}

}  // namespace truecut::sim::parts
