// Tool-centre placement and the whole field pipeline on synthetic scans with
// known displacements.
#include "truecut/offline/field_pipeline.hpp"
#include "truecut/offline/tool_centre_placement.hpp"
#include "truecut/offline/tool_path.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <random>
#include <string>

#include "offline_geometry_util.hpp"
#include "truecut/interp/interpreter.hpp"

namespace truecut::offline {
namespace {

interp::CanonProgram run(const std::string& program, const std::string& tools) {
  interp::InterpreterOptions o;
  o.tools = interp::ToolTable::parse(tools, "tools.tbl");
  return interp::Interpreter(std::move(o)).run_text(program, "test.ngc");
}

const std::string kHeader = "G21 G17 G40 G49 G80 G90 G94\nG54\n";

TEST(CutterDistance, FlatBallAndBullNose) {
  const Eigen::Vector3d tip(0, 0, 0), axis(0, 0, 1);
  const ToolShape flat{1, 2.0, 0.0, 10.0}, ball{2, 3.0, 3.0, 10.0}, bull{3, 2.0, 0.5, 10.0};
  // Flank of the flat end mill: 0.5 mm outside, normal radial.
  CutterDistance d = cutter_distance(flat, tip, axis, {2.5, 0, 4});
  EXPECT_NEAR(d.distance_mm, 0.5, 1e-12);
  EXPECT_NEAR(d.normal.x(), 1.0, 1e-12);
  // On the flat bottom: distance 0, normal −axis.
  d = cutter_distance(flat, tip, axis, {1.0, 0.3, 0});
  EXPECT_NEAR(d.distance_mm, 0.0, 1e-12);
  EXPECT_NEAR(d.normal.z(), -1.0, 1e-12);
  // Below the ball: the ball centre is at R above the tip.
  d = cutter_distance(ball, tip, axis, {0.4, 0, -0.2});
  EXPECT_NEAR(d.distance_mm, std::hypot(0.4, 3.2) - 3.0, 1e-12);
  // Bull nose corner: torus of tube radius 0.5 about the circle ρ = 1.5, h = 0.5.
  d = cutter_distance(bull, tip, axis, {2.5, 0, 0});
  EXPECT_NEAR(d.distance_mm, std::hypot(1.0, 0.5) - 0.5, 1e-12);
  // Inside the flank: negative.
  EXPECT_NEAR(cutter_distance(flat, tip, axis, {1.9, 0, 5}).distance_mm, -0.1, 1e-12);
}

// A flat end mill Ø2 cuts the wall y = 0.8 (material at y < 0.8) with its
// flank, tip at z = 2, along +x: the wall point (x0, 0.8, z0) is cut with
// the tip at (x0, 1.8, 2) for every z0 in [2, 2 + cutting length].
TEST(ToolCentrePlacement, FlatEndMillSideCut) {
  const auto program =
      run(kHeader + "T1 M6\nG43 H1\nG0 X-5 Y1.8 Z10\nG1 Z2 F300\nG1 X5\nG0 Z10\nM30\n",
          "T1 P1 D2 Z35\n");
  const ToolPath path = sample_tool_path(program);
  ASSERT_GT(path.samples.size(), 100u);
  const std::vector<ToolShape> tools{{1, 1.0, 0.0, 6.0}};
  std::vector<Eigen::Vector3d> p, n;
  for (double z0 : {2.0, 3.3, 7.9}) {
    for (double x0 : {-3.0, 0.0, 2.71}) {
      p.emplace_back(x0, 0.8, z0);
      n.emplace_back(0, 1, 0);
    }
  }
  p.emplace_back(0.0, 0.8, 8.5);  // above the cutting length
  n.emplace_back(0, 1, 0);
  p.emplace_back(0.0, -0.8, 3.0);  // the far wall: never touched
  n.emplace_back(0, -1, 0);
  p.emplace_back(0.0, 0.8, 3.0);  // right place, but facing away from the tool
  n.emplace_back(0, -1, 0);
  const PlacementResult r = place_at_tool_centre(p, n, path, tools);
  ASSERT_EQ(r.tools.size(), 1u);
  ASSERT_EQ(r.tools[0].points.size(), 9u);
  EXPECT_EQ(r.uncut_points, 3);
  for (const PointPlacement& pp : r.tools[0].points) {
    ASSERT_LT(pp.point, 9u);
    const Eigen::Vector3d& q = p[pp.point];
    // Within half a path step along the cut, plus the 1 µm tie band (0.045 mm at R 1).
    EXPECT_NEAR(pp.tcp_mm.x(), q.x(), 0.05 + 0.045) << pp.point;
    EXPECT_NEAR(pp.tcp_mm.y(), 1.8, 1e-12);
    EXPECT_NEAR(pp.tcp_mm.z(), 2.0, 1e-12);
    EXPECT_LE(std::abs(pp.distance_mm), 1e-3);
  }
}

// Two levels touch the same wall point with the flank: the first in program
// order takes it (the level whose tip is just below the point).
TEST(ToolCentrePlacement, FirstOfEquallyCloseLevelsWins) {
  const auto program = run(kHeader +
                               "T1 M6\nG43 H1\nG0 X-5 Y1.8 Z10\nG1 Z5 F300\nG1 X5\nG0 Z10\n"
                               "G0 X-5\nG1 Z4\nG1 X5\nG0 Z10\nM30\n",
                           "T1 P1 D2 Z35\n");
  const ToolPath path = sample_tool_path(program);
  const std::vector<ToolShape> tools{{1, 1.0, 0.0, 20.0}};
  const std::vector<Eigen::Vector3d> p{{0.0, 0.8, 5.5}, {0.0, 0.8, 4.5}}, n{{0, 1, 0}, {0, 1, 0}};
  const PlacementResult r = place_at_tool_centre(p, n, path, tools);
  ASSERT_EQ(r.tools.at(0).points.size(), 2u);
  EXPECT_NEAR(r.tools[0].points[0].tcp_mm.z(), 5.0, 1e-12);
  EXPECT_NEAR(r.tools[0].points[1].tcp_mm.z(), 4.0, 1e-12);
}

// A ball end mill R 3 under TRAORI with A = 20°, C = 0 (axis tilted towards
// +Y) runs its ball centre at z = 3 over the plane z = 0: the plane point P
// (normal +z) is cut with the ball centre at P + 3·n, so the tip (the TCP)
// is at P + 3·n − 3·axis = P + (0, −3 sin 20°, 3 − 3 cos 20°).
TEST(ToolCentrePlacement, BallEndMillTiltedAxis) {
  const double a = 20.0 * std::numbers::pi / 180.0;
  const double ty = -3.0 * std::sin(a), tz = 3.0 - 3.0 * std::cos(a);
  char moves[512];
  std::snprintf(moves, sizeof moves,
                "T1 M6\nG43 H1\nTRAORI\nG0 X-10 Y%.6f Z20 A20 C0\nG1 Z%.6f F500\nG1 X10\n"
                "G0 Z20\nTRAFOOF\nM30\n",
                ty, tz);
  const auto program = run(kHeader + moves, "T1 P1 D6 Z60\n");
  const ToolPath path = sample_tool_path(program);
  ASSERT_GT(path.samples.size(), 100u);
  EXPECT_NEAR(path.samples.back().axis.y(), std::sin(a), 1e-12);
  const std::vector<ToolShape> tools{{1, 3.0, 3.0, 12.0}};
  std::vector<Eigen::Vector3d> p, n;
  for (double x0 : {-5.0, 0.04, 6.5}) {
    p.emplace_back(x0, 0.0, 0.0);
    n.emplace_back(0, 0, 1);
  }
  p.emplace_back(0.0, 1.0, 0.0);  // 1 mm beside the cut: the ball stays 0.17 mm above it
  n.emplace_back(0, 0, 1);
  const PlacementResult r = place_at_tool_centre(p, n, path, tools);
  ASSERT_EQ(r.tools.at(0).points.size(), 3u);
  EXPECT_EQ(r.cut[3], 0);
  for (const PointPlacement& pp : r.tools[0].points) {
    const Eigen::Vector3d& q = p[pp.point];
    EXPECT_NEAR(pp.tcp_mm.x(), q.x(), 0.05 + 0.078);  // step/2 + tie band at R 3
    EXPECT_NEAR(pp.tcp_mm.y(), q.y() + ty, 1e-5);     // the program rounds to 1e-6
    EXPECT_NEAR(pp.tcp_mm.z(), q.z() + tz, 1e-5);
  }
}

TEST(ToolPath, ArcsRotariesAndUnsupportedMoves) {
  const auto program = run(kHeader +
                               "T1 M6\nG43 H1\nG0 X10 Y0 Z0\nG3 X0 Y10 I-10 J0 F300\nG0 Z5\n"
                               "G0 C30\nG1 X5 F300\nM30\n",
                           "T1 P1 D6 Z60\n");
  const ToolPath path = sample_tool_path(program);
  // Quarter circle of radius 10: 15.7 mm at ≤ 0.1 mm → 158 samples + start.
  ASSERT_EQ(path.samples.size(), 159u);
  for (const ToolPathSample& s : path.samples) {
    EXPECT_NEAR(std::hypot(s.tip_mm.x(), s.tip_mm.y()), 10.0, 1e-9);
    EXPECT_LE(s.tip_mm.x(), 10.0 + 1e-12);
  }
  EXPECT_EQ(path.skipped_rotated_moves, 1);  // the G1 with C at 30° outside TRAORI
  EXPECT_EQ(path.first_skipped_line, 9);
}

// --- the whole pipeline ------------------------------------------------------

using Displacement = std::function<double(double, double)>;  // along +z, mm

struct PlateCase {
  TriangleMesh nominal, scan;
  interp::CanonProgram program;
  std::vector<ToolShape> tools{{1, 3.0, 3.0, 15.0}};
};

// Nominal: the plate z = 0 over [0, 40] × [0, 20] mm, 1 mm pitch. Scan: the
// same plate at 0.5 mm pitch (another triangulation) at z = w(x, y) plus
// N(0, σ). Program: a ball end mill R 3, axis +z, raster along x at 0.5 mm
// stepover with its tip on the nominal surface, so the tip path is the
// surface itself.
PlateCase plate_case(const Displacement& w, double sigma_mm, unsigned seed = 7) {
  PlateCase c;
  c.nominal = test_geo::plate(40, 20, 40, 20, [](double, double) { return 0.0; });
  c.scan = test_geo::plate(40, 20, 80, 40, w);
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  if (sigma_mm > 0)
    for (auto& v : c.scan.vertices_mm)
      v.z() += sigma_mm * noise(rng);
  std::string prog = kHeader + "T1 M6\nG43 H1\nG0 X2 Y2 Z10\nG1 Z0 F1000\n";
  bool forward = true;
  for (int k = 0; k <= 32; ++k) {
    const double y = 2.0 + 0.5 * k;
    prog += "G1 Y" + std::to_string(y) + "\nG1 X" + (forward ? "38" : "2") + "\n";
    forward = !forward;
  }
  prog += "G0 Z10\nM30\n";
  c.program = run(prog, "T1 P1 D6 Z50\n");
  return c;
}

FieldPipelineResult run_case(const PlateCase& c, FieldPipelineOptions o = {}) {
  FieldPipelineInputs in;
  in.nominal = &c.nominal;
  in.scan = &c.scan;
  in.program = &c.program;
  in.tools = c.tools;
  o.register_scan = false;  // the scan is in the workpiece frame: the displacement is the error
  o.fit.spacing_mm = 1.0;
  return run_field_pipeline(in, o);
}

struct FieldError {
  double rms_mm = 0, max_mm = 0, max_lateral_mm = 0;
  int points = 0;
};

// Field at the tool-centre path points inside [6, 34] × [5, 15] (away from the
// border of the measured region) against minus the displacement.
FieldError field_error(const FieldPipelineResult& r, const Displacement& w) {
  FieldError e;
  double sum2 = 0;
  for (const ToolPathSample& s : r.path.samples) {
    const Eigen::Vector3d& p = s.tip_mm;
    if (p.x() < 6 || p.x() > 34 || p.y() < 5 || p.y() > 15 || p.z() > 1e-9) continue;
    const rt::FieldSample f = r.fit->field.evaluate(1, p);
    EXPECT_EQ(f.status, rt::FieldStatus::ok);
    const double dz = f.correction_mm.z() + w(p.x(), p.y());
    sum2 += dz * dz;
    e.max_mm = std::max(e.max_mm, std::abs(dz));
    e.max_lateral_mm = std::max(e.max_lateral_mm, f.correction_mm.head<2>().norm());
    ++e.points;
  }
  e.rms_mm = std::sqrt(sum2 / std::max(e.points, 1));
  return e;
}

const Displacement kConstant = [](double, double) { return 0.05; };
const Displacement kLinear = [](double x, double y) { return 0.02 + 0.002 * x - 0.001 * y; };
// Cantilever clamped at x = 0, 0.1 mm at x = 40.
const Displacement kBending = [](double x, double) {
  const double s = x / 40.0;
  return 0.1 * s * s * (3.0 - s) / 2.0;
};

TEST(FieldPipeline, RecoversKnownDisplacementsWithoutNoise) {
  for (const auto& [name, w] : {std::pair{"constant", kConstant}, std::pair{"linear", kLinear},
                                std::pair{"bending", kBending}}) {
    const PlateCase c = plate_case(w, 0.0);
    const FieldPipelineResult r = run_case(c);
    const FieldError e = field_error(r, w);
    ASSERT_GT(e.points, 5000) << name;
    // Rays are exact on these planes; the truss leaves a linear field alone
    // and bends the bending line by kb/kc·h²·w'' < 0.2 µm; the fit's residual
    // is below a micrometre.
    EXPECT_LT(e.max_mm, 2e-3) << name;
    EXPECT_LT(e.rms_mm, 1e-3) << name;
    EXPECT_LT(e.max_lateral_mm, 1e-3) << name;
    EXPECT_EQ(r.placement.tools.size(), 1u);
    // The rim of the plate (no tool reaches x < 1.5 or x > 38.5 within the
    // contact tolerance) stays out of the layer.
    EXPECT_GT(r.placement.uncut_points, 0) << name;
    for (std::size_t i = 0; i < r.points.size(); ++i) {
      const Eigen::Vector3d& p = r.points.positions_mm[i];
      if (p.x() <= 1.0 || p.x() >= 39.0 || p.y() <= 1.0 || p.y() >= 19.0) {
        EXPECT_EQ(r.placement.cut[i], 0);
      }
      if (p.x() >= 2.0 && p.x() <= 38.0 && p.y() >= 2.0 && p.y() <= 18.0) {
        EXPECT_EQ(r.placement.cut[i], 1);
      }
    }
  }
}

// With 20 and 50 µm of scanner noise the field at the path points stays
// well inside the noise: the truss (×0.51) and the fit's regularisation
// both smooth. Measured RMS/σ is written to docs/offline.md.
TEST(FieldPipeline, NoiseIsNotPassedOn) {
  for (double sigma : {0.02, 0.05}) {
    for (const auto& [name, w] : {std::pair{"linear", kLinear}, std::pair{"bending", kBending}}) {
      const PlateCase c = plate_case(w, sigma);
      const FieldPipelineResult r = run_case(c);
      const FieldError e = field_error(r, w);
      std::printf("sigma %.3f mm, %s: field error RMS %.4f mm (%.2f sigma), max %.4f mm\n", sigma,
                  name, e.rms_mm, e.rms_mm / sigma, e.max_mm);
      EXPECT_LT(e.rms_mm, 0.5 * sigma) << name;  // measured 0.44 σ
      EXPECT_LT(e.max_mm, 1.5 * sigma) << name;
    }
  }
}

TEST(FieldPipeline, StatisticsAndAdaptedMesh) {
  const PlateCase c = plate_case(kConstant, 0.0);
  const FieldPipelineResult r = run_case(c);
  // Error vectors: +0.05 mm along +z at every valid point; the rim (within
  // 0.5 mm of the open boundary) is invalid.
  EXPECT_NEAR(r.error_statistics.mean_normal_mm, 0.05, 1e-9);
  EXPECT_NEAR(r.error_statistics.max_length_mm, 0.05, 1e-9);
  const double rim = 2 * 41 + 2 * 19;
  EXPECT_NEAR(r.error_statistics.percent_invalid, 100.0 * rim / (41 * 21), 1e-9);
  EXPECT_NEAR(r.compensation_statistics.mean_mm.z(), -0.05, 1e-9);
  EXPECT_NEAR(r.max_correction_mm, 0.05, 1e-9);
  // The adapted mesh: every vertex moved by −0.05 mm (the truss fills the rim).
  ASSERT_EQ(r.adapted.vertices_mm.size(), c.nominal.vertices_mm.size());
  for (std::size_t v = 0; v < c.nominal.vertices_mm.size(); ++v)
    EXPECT_NEAR(
        (r.adapted.vertices_mm[v] - c.nominal.vertices_mm[v] - Eigen::Vector3d(0, 0, -0.05)).norm(),
        0.0, 1e-9);
  EXPECT_EQ(r.matrix.size(), r.points.size());
  EXPECT_FALSE(r.stages.empty());
}

TEST(FieldPipeline, SampledPointsAndSphereMethod) {
  const PlateCase c = plate_case(kLinear, 0.0);
  FieldPipelineOptions o;
  o.spacing_mm = 0.7;
  FieldError e = field_error(run_case(c, o), kLinear);
  EXPECT_LT(e.max_mm, 2e-3);
  // Sphere method on the scan's vertices as a cloud (0.5 mm pitch: 4 pt/mm²,
  // Rs 1.5 mm holds ~28 points).
  PlateCase cloud = c;
  cloud.scan.triangles.clear();
  o = {};
  o.method = ErrorMethod::sphere;
  e = field_error(run_case(cloud, o), kLinear);
  EXPECT_LT(e.max_mm, 2e-3);
}

TEST(FieldPipeline, NothingCutIsAnError) {
  PlateCase c = plate_case(kConstant, 0.0);
  c.program =
      run(kHeader + "T1 M6\nG43 H1\nG0 X2 Y2 Z10\nG1 Z5 F1000\nG1 X30\nM30\n", "T1 P1 D6 Z50\n");
  EXPECT_THROW(run_case(c), std::invalid_argument);
}

}  // namespace
}  // namespace truecut::offline
