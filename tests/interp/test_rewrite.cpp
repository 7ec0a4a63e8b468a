// truecut::interp::rewrite_program: lines outside the operation byte for
// byte, constant and zero compensation, arcs, TRAORI and joint-space moves,
// G93 feeds, field vs matrix, and the bad-input cases.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <map>
#include <numbers>
#include <set>

#include "rewrite_test_util.hpp"
#include "truecut/interp/error.hpp"
#include "truecut/interp/operations.hpp"
#include "truecut/interp/rewrite.hpp"
#include "truecut/interp/rs274_format.hpp"

namespace truecut::interp {
namespace {

using V = Eigen::Vector3d;

const char* kTools = "T1 P1 D2 Z35\nT2 P2 D4 Z40\n";

// The tool radius is D / 2 of the tool in the spindle: T1 1 mm, T2 2 mm.
RewriteOptions options(const std::string& op, CutType type) {
  RewriteOptions o;
  o.operation = op;
  o.type = type;
  o.interpreter.tools = ToolTable::parse(kTools, "tools.tbl");
  return o;
}

// Compensation points on a grid in the plane z = z0 over [x0,x1] x [y0,y1].
using testing::plane_matrix;

// Straight feeds of operation `op` in the program's coordinates.
std::vector<Axes6> feeds_of(const std::string& text, const std::string& op) {
  InterpreterOptions io;
  io.tools = ToolTable::parse(kTools, "tools.tbl");
  const auto prog = Interpreter(io).run_text(text, "o.ngc");
  std::vector<Axes6> out;
  for (const auto& c : prog.calls)
    if (c.context.operation == op)
      if (const auto* f = std::get_if<StraightFeed>(&c.op)) out.push_back(f->end);
  return out;
}

double distance_to_segment(const V& p, const V& a, const V& b) {
  const V d = b - a;
  const double t = std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
  return (a + t * d - p).norm();
}

// A face-milling operation between two others.
const char* kThreeOps =
    "%\n"
    "(OPERATION: FIRST)\n"
    "G21 G17 G90 G94 G54\n"
    "T1 M6\n"
    "G43 H1\n"
    "G0 X-5 Y0 Z5\n"
    "G1 Z0 F100\n"
    "G1 X5 F300\n"
    "G0 Z5\n"
    "(OPERATION: FACE)\r\n"
    "T2 M6\r\n"
    "G43 H2\r\n"
    "S12000 M3\r\n"
    "G0 X-8 Y-2 Z5\r\n"
    "G1 Z0 F200\r\n"
    "N40 G1 X8 F600 (pass 1)\r\n"
    "Y2\r\n"
    "X-8\r\n"
    "G0 Z5\r\n"
    "(OPERATION: LAST)\n"
    "G1 X0 Y0 Z1 F100\n"
    "X1\n"
    "G0 Z20\n"
    "M30\n"
    "%\n";

TEST(Rewrite, LinesOutsideTheRewrittenMovesStayByteForByte) {
  // Points on the face z = 0 over x, y in [-4, 4], shifting by (0, 0, 0.05).
  const auto m = plane_matrix(-4, 4, -4, 4, 0, 0.5, V(0, 0, 0.05));
  RewriteOptions o = options("FACE", CutType::kFace);
  o.reach_mm = 0.6;
  const RewriteResult r = rewrite_program(kThreeOps, "p.ngc", m, o);
  const std::string in = kThreeOps;
  // Everything up to the first rewritten line, and from the retract on.
  const size_t first = in.find("N40");
  EXPECT_EQ(r.text.substr(0, first), in.substr(0, first));
  const size_t tail = in.find("G0 Z5\r\n(OPERATION: LAST)");
  ASSERT_NE(tail, std::string::npos);
  EXPECT_EQ(r.text.substr(r.text.size() - (in.size() - tail)), in.substr(tail));
  // The rewritten line keeps its N number and comment, ends in CRLF.
  EXPECT_NE(r.text.find("N40 (pass 1)\r\nX-7.5000 Y-2.0000 Z0.0000 F600\r\n"), std::string::npos)
      << r.text;
  EXPECT_EQ(r.summary.moves_read, 6);
  // The two passes over the face; the rapids, the plunge and the step-over
  // Y2 at x = 8 (2 mm beyond the disc's reach) get no compensation.
  EXPECT_EQ(r.summary.moves_rewritten, 2);
  EXPECT_EQ(r.summary.moves_kept, 4);
  EXPECT_EQ(r.summary.rapids_rewritten, 0);
  EXPECT_NEAR(r.summary.max_compensation_mm, 0.05, 1e-15);
  EXPECT_NEAR(r.summary.mean_compensation_mm, 0.05, 1e-15);
}

TEST(Rewrite, ConstantOffsetShiftsEveryDensifiedPointByExactlyThatOffset) {
  const V offset(0.01, -0.02, 0.03);
  const auto m = plane_matrix(-10, 10, -4, 4, 0, 0.5, offset);
  RewriteOptions o = options("FACE", CutType::kFace);
  o.reach_mm = 100;  // every point compensated
  o.decimals = 6;
  const RewriteResult r = rewrite_program(kThreeOps, "p.ngc", m, o);
  const auto pts = feeds_of(r.text, "FACE");
  // Original polyline of the operation's feeds: (-8,-2,5) -> (-8,-2,0) ->
  // (8,-2,0) -> (8,2,0) -> (-8,2,0); the plunge is 5 mm, the passes 16 and 4.
  const std::vector<V> path = {V(-8, -2, 5), V(-8, -2, 0), V(8, -2, 0), V(8, 2, 0), V(-8, 2, 0)};
  ASSERT_EQ(pts.size(), 10u + 32u + 8u + 32u);
  EXPECT_EQ(r.summary.points_written, 82);
  EXPECT_EQ(r.summary.points_compensated, 82);
  for (const Axes6& p : pts) {
    const V back = V(p.x, p.y, p.z) - offset;
    double best = 1e9;
    for (size_t k = 1; k < path.size(); ++k)
      best = std::min(best, distance_to_segment(back, path[k - 1], path[k]));
    EXPECT_LE(best, 0.5e-6 * std::sqrt(3.0) + 1e-12) << p.x << " " << p.y << " " << p.z;
  }
  // Spacing: each piece is at most the step.
  EXPECT_NEAR(pts[1].z - pts[0].z, -0.5, 1e-6);
}

TEST(Rewrite, ZeroMatrixLeavesTheProgramIdenticalOrOnItsPath) {
  const auto m = plane_matrix(-10, 10, -4, 4, 0, 0.5, V::Zero());
  RewriteOptions o = options("FACE", CutType::kFace);
  o.reach_mm = 100;
  const RewriteResult same = rewrite_program(kThreeOps, "p.ngc", m, o);
  EXPECT_EQ(same.text, kThreeOps);
  EXPECT_EQ(same.summary.moves_rewritten, 0);
  EXPECT_EQ(same.summary.points_written, 0);

  o.keep_unchanged_moves = false;
  o.decimals = 6;
  const RewriteResult all = rewrite_program(kThreeOps, "p.ngc", m, o);
  EXPECT_EQ(all.summary.moves_rewritten, 4);
  for (const Axes6& p : feeds_of(all.text, "FACE")) {
    const V q(p.x, p.y, p.z);
    const double d = std::min({distance_to_segment(q, V(-8, -2, 5), V(-8, -2, 0)),
                               distance_to_segment(q, V(-8, -2, 0), V(8, -2, 0)),
                               distance_to_segment(q, V(8, -2, 0), V(8, 2, 0)),
                               distance_to_segment(q, V(8, 2, 0), V(-8, 2, 0))});
    EXPECT_LE(d, 1e-6);
  }
}

TEST(Rewrite, ArcsAreDensifiedOnTheirCircle) {
  const char* prog =
      "G21 G17 G90 G94\n(OPERATION: RING)\nT1 M6\nG43 H1\nG0 X10 Y0 Z0\n"
      "G1 X10 Y0 Z-1 F100\nG3 X0 Y10 I-10 J0 F500\nG2 X10 Y0 Z-2 I0 J-10\nG0 Z10\nM30\n";
  CompensationMatrixData m;
  m.positions_mm = {V(0, 0, -1)};
  m.vectors_mm = {V::Zero()};
  m.valid = {1};
  m.surface_ids = {0};
  RewriteOptions o = options("RING", CutType::kPeripheral);
  o.keep_unchanged_moves = false;
  o.reach_mm = 0.1;
  o.decimals = 7;
  o.step_mm = 0.25;
  const RewriteResult r = rewrite_program(prog, "ring.ngc", m, o);
  const auto pts = feeds_of(r.text, "RING");
  // Plunge 1 mm (4 pieces), quarter arc 15.708 mm (63), then the helix
  // (quarter circle the other way, 1 mm down; 15.74 mm: 63 pieces).
  ASSERT_EQ(pts.size(), 4u + 63u + 63u);
  for (size_t k = 4; k < pts.size(); ++k) {
    EXPECT_NEAR(std::hypot(pts[k].x, pts[k].y), 10.0, 1e-6);
    EXPECT_GE(pts[k].y, -1e-6);
  }
  // Helix: Z linear in the angle (clockwise from 90 deg to 0 deg).
  const Axes6& mid = pts[4 + 63 + 31];
  const double angle = std::atan2(mid.y, mid.x);
  EXPECT_NEAR(mid.z, -1.0 - (M_PI / 2 - angle) / (M_PI / 2), 1e-6);
}

// A small arc (a shaft corner: tool-centre radius 1 mm) at the default
// 0.5 mm step would be 4 chords with a 19 um sagitta, all of it inside the
// corner; the chord tolerance adds pieces until no chord leaves the arc by
// more than 1 um.
TEST(Rewrite, ArcChordsStayWithinTheChordToleranceOfTheArc) {
  const char* prog =
      "G21 G17 G90 G94\n(OPERATION: CORNER)\nT1 M6\nG43 H1\nG0 X0 Y1 Z0\n"
      "G1 X0 Y1 Z-1 F100\nG2 X1 Y0 I0 J-1 F500\nG0 Z10\nM30\n";
  CompensationMatrixData m;
  m.positions_mm = {V(0, 0, -1)};
  m.vectors_mm = {V::Zero()};
  m.valid = {1};
  m.surface_ids = {0};
  RewriteOptions o = options("CORNER", CutType::kPeripheral);
  o.keep_unchanged_moves = false;
  o.reach_mm = 0.1;
  o.decimals = 7;
  ASSERT_DOUBLE_EQ(o.step_mm, 0.5);
  ASSERT_DOUBLE_EQ(o.chord_tolerance_mm, 0.001);
  const RewriteResult r = rewrite_program(prog, "corner.ngc", m, o);
  const auto pts = feeds_of(r.text, "CORNER");
  // Plunge 1 mm (2 pieces), then the quarter arc: 1.571 mm would be 4
  // pieces by the step; the 1 um sagitta needs 18 (0.0895 rad each).
  ASSERT_EQ(pts.size(), 2u + 18u);
  double worst_sagitta_mm = 0;
  for (size_t k = 2; k < pts.size(); ++k) {
    const Axes6& a = pts[k - 1];
    const Axes6& b = pts[k];
    EXPECT_NEAR(std::hypot(b.x, b.y), 1.0, 1e-6);
    const double mid_radius = std::hypot(0.5 * (a.x + b.x), 0.5 * (a.y + b.y));
    worst_sagitta_mm = std::max(worst_sagitta_mm, 1.0 - mid_radius);
  }
  EXPECT_LE(worst_sagitta_mm, 0.001 + 1e-7);
  EXPECT_GT(worst_sagitta_mm, 0.0005);  // the pieces are not needlessly fine

  o.chord_tolerance_mm = 0;
  EXPECT_THROW(rewrite_program(prog, "corner.ngc", m, o), std::invalid_argument);
}

// TRAORI: X Y Z are the tip in the workpiece frame, A C the tool axis.
const char* kTraori =
    "G21 G17 G90 G94\nG54\n(OPERATION: FIVE)\nT1 M6\nG43 H1\nTRAORI\n"
    "G0 X0 Y0 Z20 A20 C0\nG1 X0 Y0 Z0 F400\nG1 X6 Y0 Z0 A30 C10 F1500\n"
    "G1 X6 Y0 Z0 A30 C-10\nG0 Z20\nTRAFOOF\nM30\n";

TEST(Rewrite, TraoriMovesShiftTheTipAndInterpolateTheAxis) {
  const V offset(0.02, 0.01, -0.04);
  CompensationMatrixData m;
  m.positions_mm = {V(0, 0, 0), V(6, 0, 0)};
  m.vectors_mm = {offset, offset};
  m.valid = {1, 1};
  m.surface_ids = {1, 1};
  RewriteOptions o = options("FIVE", CutType::kBall);
  o.reach_mm = 100;
  o.decimals = 7;
  const RewriteResult r = rewrite_program(kTraori, "five.ngc", m, o);
  const auto pts = feeds_of(r.text, "FIVE");
  // Each point minus the offset is on the programmed tip path, A and C
  // linear along the move.
  ASSERT_GT(pts.size(), 40u);
  int on_rotation = 0;
  for (const Axes6& p : pts) {
    const V tip = V(p.x, p.y, p.z) - offset;
    EXPECT_LE(std::min(distance_to_segment(tip, V(0, 0, 20), V(0, 0, 0)),
                       distance_to_segment(tip, V(0, 0, 0), V(6, 0, 0))),
              1e-6);
    if (std::fabs(tip.x() - 6) < 1e-6 && p.a == 30) ++on_rotation;
    if (tip.x() > 1e-6 && tip.x() < 6 - 1e-6) {
      EXPECT_NEAR(p.a, 20 + 10 * tip.x() / 6, 2e-6);
      EXPECT_NEAR(p.c, 10 * tip.x() / 6, 2e-6);
    }
  }
  // The pure rotation C10 -> C-10 at A30 moves the cutting edge by
  // R * 20 deg... densified too (not one point).
  EXPECT_GE(on_rotation, 2);
  EXPECT_NE(r.text.find("TRAORI\nG0 X0 Y0 Z20 A20 C0\n"), std::string::npos);
}

TEST(Rewrite, JointSpaceMovesAreShiftedInTheWorkpieceFrame) {
  // Without TRAORI the program holds joints: at A = 90 the table has turned
  // the workpiece, so a workpiece offset along +Z is a joint move along -Y
  // for these (zero) pivots (tcp_z = -sinA*u_y + cosA*u_z).
  const char* prog =
      "G21 G17 G90 G94\n(OPERATION: SIDE)\nT1 M6\nG43 H1\nG0 X0 Y0 Z5 A90\n"
      "G1 X0 Y0 Z0 F100\nG1 X4 F500\nM30\n";
  CompensationMatrixData m;
  for (int i = -50; i <= 50; ++i) {
    m.positions_mm.emplace_back(0.1 * i, 0, 0);
    m.vectors_mm.emplace_back(0, 0, 0.05);
    m.valid.push_back(1);
    m.surface_ids.push_back(0);
  }
  // The tip at joints (x, 0, 0 + 35 - 35) with A = 90: workpiece tip
  // (x, 0, 0); the compensation points lie there.
  RewriteOptions o = options("SIDE", CutType::kFace);
  o.reach_mm = 0.2;
  o.decimals = 7;
  const RewriteResult r = rewrite_program(prog, "side.ngc", m, o);
  const auto pts = feeds_of(r.text, "SIDE");
  // The plunge (machine Z, workpiece Y at A = 90: 10 pieces) reaches the
  // points only at its end; the 4 mm along X runs over them (8 pieces).
  ASSERT_EQ(pts.size(), 18u);
  for (size_t i = 10; i < pts.size(); ++i) {
    const Axes6& p = pts[i];
    rt::AcJoints j{p.x, p.y, p.z + 35, p.a, p.c};
    rt::AcTrtParams k;
    k.tool_length_mm = 35;
    const V tip = rt::forward_ac(k, j).tcp_mm;
    EXPECT_NEAR(tip.z(), 0.05, 1e-7);
    EXPECT_NEAR(tip.y(), 0.0, 1e-7);
    EXPECT_NEAR(p.y, -0.05, 1e-7);
  }
}

TEST(Rewrite, InverseTimeFeedIsRecomputedPerPiece) {
  const char* prog =
      "G21 G17 G90\n(OPERATION: G93OP)\nT1 M6\nG43 H1\nG0 X0 Y0 Z0\n"
      "G93 G1 X2 F10\nG94 G0 Z5\nM30\n";
  const auto m = plane_matrix(-1, 3, -1, 1, 0, 0.5, V(0, 0, 0.01));
  RewriteOptions o = options("G93OP", CutType::kFace);
  o.reach_mm = 0.5;
  const RewriteResult r = rewrite_program(prog, "g93.ngc", m, o);
  // 2 mm in 4 pieces of 0.5 mm: each F = 4 x 10, total time 4 / 40 = 1/10 min.
  EXPECT_NE(r.text.find("G93\nG1 X0.5000 Y0.0000 Z0.0100 F40\nX1.0000 Y0.0000 Z0.0100 F40\n"),
            std::string::npos)
      << r.text;
  // The retract names only Z: it is written with X Y Z so that X and Y come
  // back from the compensated point; G94 stays on its own line.
  EXPECT_NE(r.text.find("X2.0000 Y0.0000 Z0.0100 F40\nG94\nG0 X2 Y0 Z5\nM30\n"), std::string::npos)
      << r.text;
  EXPECT_EQ(r.summary.rapids_rewritten, 1);
}

TEST(Rewrite, FieldAndMatrixAgreeOnAConstantOffset) {
  const V offset(0.015, -0.025, 0.035);
  rt::FieldGrid g;
  g.origin_mm = V(-20, -10, -10);
  g.spacing_mm = V(1, 1, 1);
  g.dims = {41, 21, 21};
  std::vector<rt::FieldLayer> layers(2);
  for (int t = 0; t < 2; ++t) {
    layers[t].tool = t + 1;
    layers[t].nodes.assign(g.node_count(), rt::FieldNode{offset.x(), offset.y(), offset.z(), 1.0});
  }
  const rt::CorrectionField field(g, layers);
  const auto m = plane_matrix(-10, 10, -4, 4, 0, 0.5, offset);
  RewriteOptions o = options("FACE", CutType::kFace);
  o.reach_mm = 100;
  o.decimals = 6;
  const auto a = feeds_of(rewrite_program(kThreeOps, "p.ngc", m, o).text, "FACE");
  const auto b = feeds_of(rewrite_program(kThreeOps, "p.ngc", field, o).text, "FACE");
  ASSERT_EQ(a.size(), b.size());
  for (size_t k = 0; k < a.size(); ++k)
    for (int ax = 0; ax < 6; ++ax)
      EXPECT_NEAR(a[k][ax], b[k][ax], 1.0000001e-6);
  EXPECT_GT(rewrite_program(kThreeOps, "p.ngc", field, o).summary.points_covered, 0);
  // Inside the grid but without a valid node (surfaces the field did not
  // compensate) the operation is covered and gets nothing: what `truecut
  // rewrite` writes unchanged with a note, where a field that does not
  // cover it at all is refused (CliRewrite.ACompensationThatReachesNoPoint...).
  std::vector<rt::FieldLayer> invalid = layers;
  for (auto& layer : invalid)
    for (auto& node : layer.nodes)
      node.weight = 0.0;
  const RewriteResult none =
      rewrite_program(kThreeOps, "p.ngc", rt::CorrectionField(g, invalid), o);
  EXPECT_EQ(none.text, kThreeOps);
  EXPECT_EQ(none.summary.points_compensated, 0);
  EXPECT_GT(none.summary.points_covered, 0);
  // Outside the grid the field gives nothing and covers nothing: the program
  // stays as it was.
  g.origin_mm = V(100, 100, 100);
  const rt::CorrectionField away(g, layers);
  const RewriteResult outside = rewrite_program(kThreeOps, "p.ngc", away, o);
  EXPECT_EQ(outside.text, kThreeOps);
  EXPECT_EQ(outside.summary.points_covered, 0);
}

// Issue 19: a field that turns the tool. In joint space (no TRAORI, A = C = 0
// in the program) the rewriter turns A and C as truecut_comp does in joint
// mode and moves X Y Z so that the tip lands where the translation says,
// about the machine's pivots (here 100 mm below the part); the rapid after
// the operation brings A and C back. The oracle is the forward kinematics:
// the written joints give the tilted axis normalise(z + r x z) and the
// original tip plus the translation.
TEST(Rewrite, AFieldRotationTurnsAAndKeepsTheTipOnItsTarget) {
  const char* prog =
      "G21 G17 G90 G94\n(OPERATION: SIDE)\nT1 M6\nG43 H1\nG0 X0 Y0 Z5\n"
      "G1 X0 Y0 Z0 F100\nG1 X4 F500\n(OPERATION: AFTER)\nG0 Z10\nG0 X8\nM30\n";
  const V rotation(5e-4, 0, 0), translation(0.01, 0, -0.004);
  rt::FieldGrid g;
  g.origin_mm = V(-20, -10, -10);
  g.spacing_mm = V(1, 1, 1);
  g.dims = {41, 21, 21};
  std::vector<rt::FieldLayer> layers(1);
  layers[0].tool = 1;
  layers[0].nodes.assign(g.node_count(),
                         rt::FieldNode{translation.x(), translation.y(), translation.z(), 1.0});
  layers[0].rotation_rad.assign(g.node_count(), rotation);
  const rt::CorrectionField field(g, layers);
  RewriteOptions o = options("SIDE", CutType::kPeripheral);
  o.decimals = 7;
  o.kinematics.z_rot_point_mm = -100;
  const RewriteResult r = rewrite_program(prog, "side.ngc", field, o);
  EXPECT_GT(r.summary.points_rotated, 0);
  EXPECT_NEAR(r.summary.max_rotation_rad, rotation.norm(), 1e-15);
  EXPECT_LT(r.summary.max_rotation_shortfall_rad, 1e-9);  // A gives a lean about X whole
  rt::AcTrtParams k = o.kinematics;
  k.tool_length_mm = 35;
  const V wanted_axis = (V(0, 0, 1) + rotation.cross(V(0, 0, 1))).normalized();
  const auto pts = feeds_of(r.text, "SIDE");
  ASSERT_GE(pts.size(), 8u);
  double last_x = -1;
  for (const Axes6& p : pts) {
    const rt::ToolPose pose = rt::forward_ac(k, {p.x, p.y, p.z + 35, p.a, p.c});
    EXPECT_NEAR(0.0, (pose.axis - wanted_axis).norm(), 1e-8) << p.a;
    EXPECT_NE(p.a, 0.0);
    // The tip: on the programmed path, shifted by the translation.
    const V tip = pose.tcp_mm - translation;
    EXPECT_NEAR(tip.y(), 0.0, 1e-6);
    if (tip.z() > 1e-6) continue;  // the plunge
    EXPECT_NEAR(tip.z(), 0.0, 1e-6);
    EXPECT_GE(tip.x(), last_x - 1e-6);
    last_x = tip.x();
  }
  EXPECT_NEAR(last_x, 4.0, 1e-6);
  // The retract after the operation names A and C again: back to 0.
  const std::string after = "(OPERATION: AFTER)\n";
  const auto retract = r.text.find(after + "G0 ") + after.size();
  ASSERT_GT(retract, after.size()) << r.text;
  const std::string line = r.text.substr(retract, r.text.find('\n', retract) - retract);
  EXPECT_NE(line.find(" A0"), std::string::npos) << line;
  EXPECT_NE(line.find(" C0"), std::string::npos) << line;
}

// Under TRAORI the tip stays on its target and A and C turn the axis as
// the machine's forward kinematics says: point for point against the same
// rewrite without the rotation, the written A and C give that rewrite's
// axis tilted by r, at A 20..30 degrees both ways of leaning.
TEST(Rewrite, AFieldRotationUnderTraoriTurnsAAndCAboutTheTip) {
  const V rotation(3e-4, -2e-4, 1e-4), translation(0.01, -0.02, 0.005);
  rt::FieldGrid g;
  g.origin_mm = V(-20, -10, -10);
  g.spacing_mm = V(1, 1, 1);
  g.dims = {41, 21, 41};
  auto field_with = [&](const V& r) {
    std::vector<rt::FieldLayer> layers(1);
    layers[0].tool = 1;
    layers[0].nodes.assign(g.node_count(),
                           rt::FieldNode{translation.x(), translation.y(), translation.z(), 1.0});
    layers[0].rotation_rad.assign(g.node_count(), r);
    return rt::CorrectionField(g, layers);
  };
  RewriteOptions o = options("FIVE", CutType::kBall);
  o.decimals = 9;
  const RewriteResult turned = rewrite_program(kTraori, "five.ngc", field_with(rotation), o);
  const RewriteResult plain = rewrite_program(kTraori, "five.ngc", field_with(V::Zero()), o);
  EXPECT_LT(turned.summary.max_rotation_shortfall_rad, 1e-9);
  const auto a = feeds_of(turned.text, "FIVE"), b = feeds_of(plain.text, "FIVE");
  ASSERT_EQ(a.size(), b.size());
  ASSERT_GT(a.size(), 40u);
  const rt::AcTrtParams k = o.kinematics;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_NEAR(0.0, (V(a[i].x, a[i].y, a[i].z) - V(b[i].x, b[i].y, b[i].z)).norm(), 1e-8);
    const V plain_axis = rt::forward_ac(k, {0, 0, 0, b[i].a, b[i].c}).axis;
    const V turned_axis = rt::forward_ac(k, {0, 0, 0, a[i].a, a[i].c}).axis;
    const V wanted = (plain_axis + rotation.cross(plain_axis)).normalized();
    EXPECT_NEAR(0.0, (turned_axis - wanted).norm(), 1e-8) << i;
  }
  // The retract inside the operation brings A and C back.
  EXPECT_NE(turned.text.find("G0 X6 Y0 Z20 A30 C-10"), std::string::npos) << turned.text;
}

// A wall x = 0 (material at x < 0) cut by the flank of a flat end mill R 1
// in five levels from the top down (tip z = 4, 3, 2, 1, 0), each level one
// G1 along Y; compensation points on the wall every 0.1 mm up to z = 8 with
// the vector (-c(z), 0, 0), c growing with z.
const char* kStepped =
    "G21 G17 G90 G94\n(OPERATION: WALL)\nT1 M6\nG43 H1\nG0 X1 Y-3 Z10\n"
    "G1 Z4 F300\nG1 Y3\nG0 Z10\nG0 Y-3\nG1 Z3\nG1 Y3\nG0 Z10\nG0 Y-3\nG1 Z2\nG1 Y3\n"
    "G0 Z10\nG0 Y-3\nG1 Z1\nG1 Y3\nG0 Z10\nG0 Y-3\nG1 Z0\nG1 Y3\nG0 Z10\nM30\n";

double wall_need_mm(double z) {
  return 0.01 + 0.004 * z;
}

CompensationMatrixData wall_matrix() {
  CompensationMatrixData m;
  for (int j = -50; j <= 50; ++j)
    for (int k = 0; k <= 80; ++k) {
      const double z = 0.1 * k;
      m.positions_mm.emplace_back(0.0, 0.1 * j, z);
      m.vectors_mm.emplace_back(-wall_need_mm(z), 0.0, 0.0);
      m.valid.push_back(1);
      m.surface_ids.push_back(1);
    }
  return m;
}

// The written X of each level's pass along Y (all its densified points).
std::map<double, std::vector<double>> x_by_level(const std::string& text) {
  std::map<double, std::vector<double>> out;
  for (const Axes6& p : feeds_of(text, "WALL"))
    if (std::fabs(p.y) < 2.9) out[std::round(p.z)].push_back(p.x);
  return out;
}

TEST(Rewrite, EveryPassLevelTakesTheMeanOfTheWallItsFlankSweeps) {
  RewriteOptions o = options("WALL", CutType::kPeripheral);
  o.reach_mm = 0.2;         // query bands every 0.1 mm, on the rows
  o.cutting_length_mm = 2;  // the flank sweeps the wall from the tip up 2 mm
  o.decimals = 7;
  const auto every = x_by_level(rewrite_program(kStepped, "w.ngc", wall_matrix(), o).text);
  o.placement = MatrixPlacement::kTip;
  const auto tip = x_by_level(rewrite_program(kStepped, "w.ngc", wall_matrix(), o).text);
  ASSERT_EQ(every.size(), 5u);
  ASSERT_EQ(tip.size(), 5u);
  for (const auto& [z, xs] : every) {
    ASSERT_FALSE(xs.empty());
    // c is linear in z: the mean over the 2 mm the flank sweeps is c at its middle.
    for (double x : xs)
      EXPECT_NEAR(x, 1.0 - wall_need_mm(z + 1.0), 1.5e-7) << "level z = " << z;
    // The source's rule takes the row at the tip.
    for (double x : tip.at(z))
      EXPECT_NEAR(x, 1.0 - wall_need_mm(z), 1.5e-7) << "level z = " << z;
  }
  // Without a cutting length the flank reaches the G43 tool length (35 mm):
  // the whole wall above the tip, up to its top at z = 8.
  o.placement = MatrixPlacement::kEveryPass;
  o.cutting_length_mm = 0;
  for (const auto& [z, xs] : x_by_level(rewrite_program(kStepped, "w.ngc", wall_matrix(), o).text))
    for (double x : xs)
      EXPECT_NEAR(x, 1.0 - wall_need_mm((z + 8.0) / 2), 0.0003) << "level z = " << z;
}

TEST(Rewrite, EveryPassFaceMillingAveragesOverTheDisc) {
  // The plane z = 0 with 0.01 mm to remove at x < 0 and 0.03 mm at x >= 0;
  // a flat end mill R 2 passes along Y at x = -0.5.
  CompensationMatrixData m;
  for (int i = -60; i <= 60; ++i)
    for (int j = -60; j <= 60; ++j) {
      m.positions_mm.emplace_back(0.1 * i, 0.1 * j, 0.0);
      m.vectors_mm.emplace_back(0.0, 0.0, i < 0 ? -0.01 : -0.03);
      m.valid.push_back(1);
      m.surface_ids.push_back(5);
    }
  const char* prog =
      "G21 G17 G90 G94\n(OPERATION: TOP)\nT2 M6\nG43 H2\nG0 X-0.5 Y-2 Z5\nG1 Z0 F300\n"
      "G1 Y2\nG0 Z5\nM30\n";
  RewriteOptions o = options("TOP", CutType::kFace);
  o.reach_mm = 0.2;
  o.decimals = 7;
  std::vector<double> z_every, z_tip;
  for (const Axes6& p : feeds_of(rewrite_program(prog, "t.ngc", m, o).text, "TOP"))
    if (std::fabs(p.y) < 1.9 && p.z < 1) z_every.push_back(p.z);
  o.placement = MatrixPlacement::kTip;
  for (const Axes6& p : feeds_of(rewrite_program(prog, "t.ngc", m, o).text, "TOP"))
    if (std::fabs(p.y) < 1.9 && p.z < 1) z_tip.push_back(p.z);
  ASSERT_FALSE(z_every.empty());
  ASSERT_EQ(z_every.size(), z_tip.size());
  // The part of the disc beyond x = 0 (0.5 mm from its centre) is
  // (R^2 acos(d/R) - d sqrt(R^2 - d^2)) / (pi R^2) = 0.3425 of its area.
  const double beyond = (4 * std::acos(0.25) - 0.5 * std::sqrt(3.75)) / (4 * std::numbers::pi);
  for (double z : z_every)
    EXPECT_NEAR(z, -0.01 - 0.02 * beyond, 0.0005);
  // The source's rule: the points nearest the tip only.
  for (double z : z_tip)
    EXPECT_NEAR(z, -0.01, 1e-7);
}

TEST(Rewrite, SmoothingAveragesNeighboursOfTheSameSurfaceOnly) {
  // Surface 1: 0.02 mm along z with +-0.01 mm of checkerboard noise; surface
  // 2 at the same places with 0.1 mm (not selected: it must not leak in).
  CompensationMatrixData m;
  for (int s = 1; s <= 2; ++s)
    for (int i = -30; i <= 30; ++i)
      for (int j = -30; j <= 30; ++j) {
        m.positions_mm.emplace_back(0.3 * i, 0.3 * j, 0.0);
        const double noise = (i + j) % 2 == 0 ? 0.01 : -0.01;
        m.vectors_mm.emplace_back(0.0, 0.0, s == 1 ? 0.02 + noise : 0.1);
        m.valid.push_back(1);
        m.surface_ids.push_back(s);
      }
  RewriteOptions o = options("FACE", CutType::kFace);
  o.placement = MatrixPlacement::kTip;
  o.reach_mm = 0.3;
  o.surfaces = {1};
  o.decimals = 7;
  auto spread = [&](double radius, double& lo, double& hi) {
    o.smoothing_radius_mm = radius;
    lo = 1e9;
    hi = -1e9;
    for (const Axes6& p : feeds_of(rewrite_program(kThreeOps, "p.ngc", m, o).text, "FACE"))
      if (std::fabs(p.z) < 0.5) lo = std::min(lo, p.z), hi = std::max(hi, p.z);
  };
  double lo = 0, hi = 0;
  spread(0, lo, hi);
  EXPECT_LT(lo, 0.018) << "the noise is passed on";
  EXPECT_GT(hi, 0.022);
  spread(1.0, lo, hi);
  EXPECT_GT(lo, 0.0195) << "averaged away, and no trace of surface 2";
  EXPECT_LT(hi, 0.0205);
}

TEST(Rewrite, InchProgramsGetTheShiftInInchesWithFiveDecimals) {
  // 0.0254 mm = 0.001 in towards +Z on the face z = 0 (the matrix is in mm).
  const auto m = plane_matrix(-10, 10, -4, 4, 0, 0.5, V(0, 0, 0.0254));
  const char* prog =
      "G20 G17 G90 G94\n(OPERATION: FACE)\nT2 M6\nG43 H2\nG0 X-0.2 Y0 Z0.2\nG1 Z0 F10\n"
      "G1 X0.2 F20\nG0 Z0.2\nM30\n";
  RewriteOptions o = options("FACE", CutType::kFace);
  o.reach_mm = 100;
  const RewriteResult r = rewrite_program(prog, "inch.ngc", m, o);
  EXPECT_NE(r.text.find("\nX0.20000 Y0.00000 Z0.00100\n"), std::string::npos) << r.text;
  int on_face = 0;
  for (const Axes6& p : feeds_of(r.text, "FACE")) {  // program units: inches
    if (p.z < 0.005) {
      EXPECT_NEAR(p.z, 0.001, 1e-12);
      ++on_face;
    }
  }
  EXPECT_GE(on_face, 15);
}

template <typename E>
std::string error_of(const std::string& program, const RewriteOptions& o) {
  const auto m = plane_matrix(-10, 10, -4, 4, 0, 0.5, V(0, 0, 0.01));
  try {
    rewrite_program(program, "bad.ngc", m, o);
  } catch (const E& e) {
    return e.what();
  }
  return "no error";
}

TEST(Rewrite, BadInputIsRefusedWithAClearMessage) {
  RewriteOptions o = options("FACE", CutType::kFace);
  o.reach_mm = 100;
  EXPECT_EQ(error_of<RewriteError>(kThreeOps, options("ROUGH", CutType::kFace)),
            "bad.ngc: operation 'ROUGH' is not in the program (operations: FIRST, FACE, LAST)");
  RewriteOptions s = o;
  s.step_mm = 0;
  EXPECT_EQ(error_of<std::invalid_argument>(kThreeOps, s), "step must be > 0 mm (got 0.000000)");
  s.step_mm = -1;
  EXPECT_NE(error_of<std::invalid_argument>(kThreeOps, s), "no error");
  const std::string head = "G21 G90 G94\n(OPERATION: FACE)\nT2 M6\nG43 H2\nG0 X0 Y0 Z1\n";
  EXPECT_EQ(error_of<GcodeError>(head + "G1 Z0 F100 M0\nM30\n", o),
            "bad.ngc:6:12: M0 beside a move: this move cannot be rewritten");
  // Parameters, expressions and G91 on a feed of the operation: the line is
  // written out as its moves (test_rewrite_expansion.cpp), not refused.
  EXPECT_EQ(error_of<GcodeError>(head + "G1 X[1+1] F100\nM30\n", o), "no error");
  EXPECT_EQ(error_of<GcodeError>(head + "G91 G1 X1 F100\nM30\n", o), "no error");
  EXPECT_EQ(error_of<GcodeError>(head + "F100\nBSPLINE X1\nX2 Y1\nG1 X3\nM30\n", o),
            "bad.ngc:7: BSPLINE/CSPLINE point: spline moves cannot be rewritten as G1 moves");
  // A loop is written out move by move (test_rewrite_expansion.cpp), not refused.
  EXPECT_EQ(
      error_of<GcodeError>(head + "F100\no1 repeat [2]\nG1 X1\nG1 X0\no1 endrepeat\nM30\n", o),
      "no error");
  // G91 set before the operation: its feed is written out too.
  EXPECT_EQ(error_of<GcodeError>(
                "G21 G91 G94\n(OPERATION: FACE)\nT2 M6\nG43 H2\nG0 Z40\nG1 X1 F100\nM30\n", o),
            "no error");
}

// A canned cycle expands into several moves on its line: the rewrite cannot
// keep the cycle word, so a cycle line in the operation is refused by name
// (also a modal cycle line without the G word); cycles outside the
// operation are copied as written.
// Canned cycles in the operation stay cycles, their hole and bottom
// corrected (the cases of tests/interp/test_rewrite_cycles.cpp in detail);
// outside it they are copied.
TEST(Rewrite, CannedCyclesInTheOperationAreKeptWithTheirHolesCorrected) {
  RewriteOptions o = options("FACE", CutType::kFace);
  o.reach_mm = 100;
  const auto m = plane_matrix(-10, 10, -4, 4, 0, 0.5, V(0, 0, 0.01));
  const std::string head = "G21 G90 G94\n(OPERATION: FACE)\nT2 M6\nG43 H2\nG0 X0 Y0 Z1\n";
  const RewriteResult in_op =
      rewrite_program(head + "G98 G81 X1 Y1 Z-0.5 R0.5 F100\nX2\nG80\nM30\n", "drill.ngc", m, o);
  EXPECT_NE(in_op.text.find("\nG98 G81 R0.5 F100 X1.0000 Y1.0000 Z-0.4900\nX2.0000 Y1.0000 "
                            "Z-0.4900\nG80\n"),
            std::string::npos)
      << in_op.text;
  EXPECT_EQ(in_op.summary.holes_rewritten, 2);
  // A cycle started before the operation: its line in the operation is
  // written with its hole and bottom, the line before copied.
  const std::string modal =
      "G21 G90 G94\nT2 M6\nG43 H2\nG0 X0 Y0 Z1\nG83 X1 Y1 Z-0.5 R0.5 Q0.2 F100\n"
      "(OPERATION: FACE)\nX2\nG80\nM30\n";
  const RewriteResult from_before = rewrite_program(modal, "drill.ngc", m, o);
  EXPECT_NE(from_before.text.find("\nG83 X1 Y1 Z-0.5 R0.5 Q0.2 F100\n(OPERATION: FACE)\n"
                                  "X2.0000 Y1.0000 Z-0.4900\nG80\n"),
            std::string::npos)
      << from_before.text;
  const std::string outside =
      "G21 G90 G94\n(OPERATION: FACE)\nT2 M6\nG43 H2\nG0 X0 Y0 Z1\nG1 Z0 F100\nX2\n"
      "G0 Z1\n(OPERATION: DRILL)\nG81 X1 Y1 Z-0.5 R0.5 F100\nX2\nG80\nM30\n";
  const RewriteResult r = rewrite_program(outside, "drill.ngc", m, o);
  EXPECT_NE(r.text.find("\nG81 X1 Y1 Z-0.5 R0.5 F100\nX2\nG80\n"), std::string::npos) << r.text;
  EXPECT_GT(r.summary.moves_rewritten, 0) << r.text;  // the FACE moves were compensated
  EXPECT_EQ(r.summary.holes_rewritten, 0);
}

// Polar words (@ ^) end a move like X Y: a rewritten polar move is written
// as X Y Z (the same end in G90), kept lines keep their polar words, and
// the moves land where the polar original would have gone, shifted.
// M70/M72 around the operation are copied as written.
TEST(Rewrite, PolarMovesAreWrittenAsXYAtTheirEnd) {
  const V offset(0, 0, 0.01);
  const auto m = plane_matrix(-10, 10, -10, 10, 0, 0.5, offset);
  RewriteOptions o = options("FACE", CutType::kFace);
  o.reach_mm = 100;
  o.decimals = 6;
  const std::string program =
      "G21 G90 G94\nT2 M6\nG43 H2\nG0 X0 Y0 Z1\nM70\nG20\nM72\n(OPERATION: FACE)\n"
      "G0 @5 ^0 Z1\nG1 Z0 F100\nG1 @5 ^90 (quarter)\n^180\nG0 Z1\n(OPERATION: LAST)\n"
      "G0 @2 ^45\nM30\n";
  const RewriteResult r = rewrite_program(program, "polar.ngc", m, o);
  // The feeds of FACE, shifted back, lie on the original polyline
  // (5,0,1) -> (5,0,0) -> (0,5,0) -> (-5,0,0).
  const std::vector<V> path = {V(5, 0, 1), V(5, 0, 0), V(0, 5, 0), V(-5, 0, 0)};
  const auto pts = feeds_of(r.text, "FACE");
  ASSERT_GT(pts.size(), 3u) << r.text;
  for (const Axes6& p : pts) {
    const V back = V(p.x, p.y, p.z) - offset;
    double best = 1e9;
    for (size_t k = 1; k < path.size(); ++k)
      best = std::min(best, distance_to_segment(back, path[k - 1], path[k]));
    EXPECT_LE(best, 1e-6) << p.x << " " << p.y << " " << p.z;
  }
  EXPECT_NEAR(pts.back().x, -5, 1e-6);
  EXPECT_NEAR(pts.back().y, 0, 1e-6);
  // The rewritten lines carry no polar word; the line comment stays.
  const size_t face = r.text.find("(OPERATION: FACE)");
  const size_t last = r.text.find("(OPERATION: LAST)");
  ASSERT_NE(face, std::string::npos);
  ASSERT_NE(last, std::string::npos);
  const std::string rewritten = r.text.substr(face, last - face);
  EXPECT_EQ(rewritten.find("@5 ^90"), std::string::npos) << rewritten;
  EXPECT_EQ(rewritten.find("\n^180"), std::string::npos) << rewritten;
  EXPECT_NE(rewritten.find("(quarter)"), std::string::npos) << rewritten;
  // Lines before the operation (M70 G20 M72) and after it are byte for byte.
  EXPECT_EQ(r.text.substr(0, face), program.substr(0, program.find("(OPERATION: FACE)")));
  EXPECT_EQ(r.text.substr(last), program.substr(program.find("(OPERATION: LAST)")));
  EXPECT_GT(r.summary.moves_rewritten, 0);
  // A polar word from an expression: the line is written out as its move.
  const std::string expr =
      "G21 G90 G94\n(OPERATION: FACE)\nT2 M6\nG43 H2\nG0 X0 Y0 Z0\nG1 @5 ^[45] F100\nM30\n";
  const RewriteResult e = rewrite_program(expr, "e.ngc", m, o);
  EXPECT_NE(e.text.find("(truecut rewrite: line 6, the line, written out as the "),
            std::string::npos)
      << e.text;
  EXPECT_EQ(e.text.find("^[45]"), std::string::npos) << e.text;
}

// A program under cutter radius compensation (G41/G42) is written out in
// G40 (docs/gcode.md "Cutter radius compensation"): every compensated move
// where the compensated tool goes, the operation's corrections on top, the
// first move after the G40 exit with all of X Y Z, and a header comment that
// says so.
TEST(Rewrite, CutterCompensationIsExpandedIntoCompensatedMoves) {
  const V offset(0.01, -0.02, 0.03);
  const auto m = plane_matrix(-20, 40, -20, 40, 0, 0.5, offset);
  RewriteOptions o = options("PROFILE", CutType::kPeripheral);
  o.reach_mm = 100;
  o.decimals = 6;
  const std::string program =
      "G21 G90 G94\nT2 M6\nG43 H2\nG0 X-10 Y-10 Z1\nG41 D2\nG0 X0 Y0\n(OPERATION: PROFILE)\n"
      "G1 Z0 F300\nX20\nG3 X30 Y10 R10\nG1 Y20\nX0 (left)\n(OPERATION: END)\nY0\n"
      "G40 G0 Z5\nX-10 Y-10\nM30\n";
  const RewriteResult r = rewrite_program(program, "comp.ngc", m, o);
  EXPECT_EQ(r.text.rfind("(truecut rewrite: cutter radius compensation G41/G42 expanded", 0), 0u)
      << r.text;
  const std::string body = r.text.substr(r.text.find('\n') + 1);
  EXPECT_EQ(body.find("G41"), std::string::npos) << r.text;
  EXPECT_EQ(r.text.find("D2"), std::string::npos) << r.text;
  EXPECT_NE(r.text.find("(left)"), std::string::npos) << r.text;

  InterpreterOptions io;
  io.tools = ToolTable::parse(kTools, "tools.tbl");
  const auto original = Interpreter(io).run_text(program, "comp.ngc");
  const auto rewritten = Interpreter(io).run_text(r.text, "out.ngc");
  std::vector<Axes6> ends_out;
  for (const auto& c : rewritten.calls) {
    if (!is_motion(c.op)) continue;
    EXPECT_FALSE(c.context.cutter_comp);
    if (const auto* f = std::get_if<StraightFeed>(&c.op)) ends_out.push_back(f->end);
    if (const auto* t = std::get_if<StraightTraverse>(&c.op)) ends_out.push_back(t->end);
  }
  // Every end of the original (compensated) path is reached by the output,
  // shifted by the offset on the operation's feed moves.
  int compensated = 0;
  for (const auto& c : original.calls) {
    if (!is_motion(c.op)) continue;
    compensated += c.context.cutter_comp;
    Axes6 want = std::visit(
        [](const auto& op) -> Axes6 {
          if constexpr (requires { op.end; }) return op.end;
          return Axes6{};
        },
        c.op);
    if (c.context.operation == "PROFILE" && !std::holds_alternative<StraightTraverse>(c.op)) {
      want.x += offset.x();
      want.y += offset.y();
      want.z += offset.z();
    }
    bool found = false;
    for (const Axes6& e : ends_out)
      found = found || (std::fabs(e.x - want.x) < 1e-6 && std::fabs(e.y - want.y) < 1e-6 &&
                        std::fabs(e.z - want.z) < 1e-6);
    EXPECT_TRUE(found) << "line " << c.context.line << ": " << want.x << " " << want.y << " "
                       << want.z << "\n"
                       << r.text;
  }
  EXPECT_GE(compensated, 7);  // entry, Z, X20, corner arc, arc, Y20, X0, Y0
  // The exit starts from the compensated point: written with X Y Z.
  ASSERT_FALSE(ends_out.empty());
  EXPECT_NEAR(ends_out.back().x, -10, 1e-9);
  EXPECT_NEAR(ends_out.back().y, -10, 1e-9);
  EXPECT_NEAR(ends_out.back().z, 5, 1e-9);

  // With no correction at all the compensated moves are still written out,
  // and so is the exit move of the operation, which names only Y: it starts
  // from the compensated point and its X is the programmed one.
  const auto zero = plane_matrix(-20, 40, -20, 40, 0, 0.5, V::Zero());
  const std::string exit_in_op =
      "G21 G90 G94\nT2 M6\nG0 X-10 Y-10 Z0\n(OPERATION: PROFILE)\nG41 D2 G1 X0 Y0 F300\nX20\n"
      "Y20\nG40 G1 Y30\nM30\n";
  const RewriteResult z = rewrite_program(exit_in_op, "exit.ngc", zero, o);
  auto last_feed = [](const CanonProgram& p) {
    Axes6 end;
    for (const auto& c : p.calls)
      if (const auto* f = std::get_if<StraightFeed>(&c.op)) end = f->end;
    return end;
  };
  const Axes6 want = last_feed(Interpreter(io).run_text(exit_in_op, "exit.ngc"));
  const Axes6 got = last_feed(Interpreter(io).run_text(z.text, "z.ngc"));
  EXPECT_NEAR(want.x, 20, 1e-9);
  EXPECT_NEAR(want.y, 30, 1e-9);
  EXPECT_NEAR(got.x, want.x, 1e-9) << z.text;
  EXPECT_NEAR(got.y, want.y, 1e-9) << z.text;
  EXPECT_EQ(z.text.find("\nX20\n"), std::string::npos) << z.text;

  // Compensated moves that run more than once are written out with their
  // loop (test_rewrite_expansion.cpp): as the unrolled program's.
  const std::string loop =
      "G21 G90 G94\nT2 M6\n#<_row> = 0\nG0 X-10 Y-10 Z1\nG41 D2 G1 X0 Y0 F300\n"
      "(OPERATION: PROFILE)\no1 repeat [2]\nG1 X10 Y[#<_row>]\n#<_row> = 5\no1 endrepeat\nG40 G0 "
      "X-10\nM30\n";
  const std::string unrolled =
      "G21 G90 G94\nT2 M6\nG0 X-10 Y-10 Z1\nG41 D2 G1 X0 Y0 F300\n(OPERATION: PROFILE)\n"
      "G1 X10 Y0\nG1 X10 Y5\nG40 G0 X-10\nM30\n";
  const RewriteResult looped = rewrite_program(loop, "l.ngc", zero, o);
  const RewriteResult flat = rewrite_program(unrolled, "u.ngc", zero, o);
  EXPECT_EQ(looped.summary.expansions, 1);
  // Around moves that run once (a condition, a subroutine called once) the
  // O-words stay, and the compensated moves are written where the tool goes
  // as without them.
  const std::string plain =
      "G21 G90 G94\nT2 M6\nG0 X-10 Y-10 Z0\n(OPERATION: PROFILE)\nG41 D2 G1 X0 Y0 F300\n"
      "X20\nY20\nX0\nY0\nG40 G1 X-10 Y-10\nM30\n";
  const std::string with_o_words =
      "o<side> sub\nY20\no<side> endsub\nG21 G90 G94\nT2 M6\nG0 X-10 Y-10 Z0\n"
      "(OPERATION: PROFILE)\n#1 = 20\nG41 D2 G1 X0 Y0 F300\no2 if [#1 GT 10]\nX20\n"
      "o2 else\nX30\no2 endif\no<side> call\nX0\nY0\nG40 G1 X-10 Y-10\nM30\n";
  const RewriteResult a = rewrite_program(plain, "a.ngc", zero, o);
  const RewriteResult b = rewrite_program(with_o_words, "b.ngc", zero, o);
  EXPECT_NE(b.text.find("\no2 if [#1 GT 10]\n"), std::string::npos) << b.text;
  EXPECT_NE(b.text.find("\no<side> call\n"), std::string::npos) << b.text;
  auto feeds = [&](const std::string& text) {
    std::vector<std::string> out;
    for (const auto& c : Interpreter(io).run_text(text, "f.ngc").calls)
      if (std::holds_alternative<StraightFeed>(c.op) || std::holds_alternative<ArcFeed>(c.op))
        out.push_back(format_rs274(c.op));
    return out;
  };
  EXPECT_EQ(feeds(b.text), feeds(a.text)) << a.text << "\n" << b.text;
  EXPECT_EQ(feeds(looped.text), feeds(flat.text)) << looped.text << "\n" << flat.text;
}

// M70/M72 inside the operation are copied as written: the rewritten lines
// run under the state M72 restores (here the feed), as the originals did.
// G5.1 is refused by name at its line (the rewrite does not correct splines).
TEST(Rewrite, ModalStateLinesAreCopied) {
  RewriteOptions o = options("FACE", CutType::kFace);
  o.reach_mm = 100;
  const auto m = plane_matrix(-10, 10, -4, 4, 0, 0.5, V(0, 0, 0.01));
  const std::string program =
      "G21 G90 G94\n(OPERATION: FACE)\nT2 M6\nG43 H2\nG0 X-4 Y0 Z1\nG1 Z0 F100\nM70\n"
      "G1 X0 F40\nM72\nG1 X4\nG0 Z1\nM30\n";
  const RewriteResult r = rewrite_program(program, "m70.ngc", m, o);
  EXPECT_NE(r.text.find("\nM70\n"), std::string::npos) << r.text;
  EXPECT_NE(r.text.find("\nM72\n"), std::string::npos) << r.text;
  EXPECT_GT(r.summary.moves_rewritten, 0);
  // The feed of every feed move of the output is the original's.
  InterpreterOptions io;
  io.tools = ToolTable::parse(kTools, "tools.tbl");
  auto feeds = [&](const std::string& text) {
    std::vector<double> out;
    double f = 0;
    for (const auto& c : Interpreter(io).run_text(text, "f.ngc").calls) {
      if (const auto* s = std::get_if<SetFeedRate>(&c.op)) f = s->units_per_minute;
      if (std::holds_alternative<StraightFeed>(c.op)) out.push_back(f);
    }
    return out;
  };
  const auto before = feeds(program), after = feeds(r.text);
  ASSERT_GT(after.size(), before.size());
  EXPECT_EQ(before, (std::vector<double>{100, 40, 100}));
  EXPECT_EQ(after.back(), 100);  // restored by M72 for the last pass
  EXPECT_EQ(std::set<double>(after.begin(), after.end()), (std::set<double>{40, 100}));
  // A G52 line is copied as written; an output code on a rewritten move's
  // line is refused by name.
  const std::string g52 =
      "G21 G90 G94\n(OPERATION: FACE)\nT2 M6\nG43 H2\nG52 X1 Y0.5\nG0 X-4 Y0 Z1\nG1 Z0 F100\n"
      "G1 X0 F40\nM62 P1\nG1 X4\nG0 Z1\nM30\n";
  const RewriteResult r52 = rewrite_program(g52, "g52.ngc", m, o);
  EXPECT_NE(r52.text.find("\nG52 X1 Y0.5\n"), std::string::npos) << r52.text;
  EXPECT_NE(r52.text.find("\nM62 P1\n"), std::string::npos) << r52.text;
  EXPECT_GT(r52.summary.moves_rewritten, 0);
  EXPECT_NE(error_of<GcodeError>("G21 G90 G94\n(OPERATION: FACE)\nT2 M6\nG43 H2\nG0 X-4 Y0 Z1\n"
                                 "G1 Z0 F100\nG1 X0 M62 P1\nM30\n",
                                 o)
                .find("M62 beside a move"),
            std::string::npos);
  // A Fanuc-style subprogram run once is rewritten in place; run twice (L2)
  // its call is written out move by move, like a loop.
  const std::string m98 =
      "G21 G90 G94\n(OPERATION: FACE)\nT2 M6\nG43 H2\nG0 X-4 Y0 Z1\nG1 Z0 F100\nM98 P100\n"
      "G0 Z1\nM30\nO100\nG1 X0 F40\nG1 X4\nM99\n";
  const RewriteResult r98 = rewrite_program(m98, "m98.ngc", m, o);
  EXPECT_NE(r98.text.find("\nM98 P100\n"), std::string::npos) << r98.text;
  EXPECT_NE(r98.text.find("\nO100\n"), std::string::npos) << r98.text;
  EXPECT_GT(r98.summary.moves_rewritten, 0);
  std::string twice = m98;
  twice.replace(twice.find("M98 P100"), 8, "M98 P100 L2");
  const RewriteResult r98x2 = rewrite_program(twice, "m98.ngc", m, o);
  EXPECT_EQ(r98x2.summary.expansions, 1);
  EXPECT_EQ(r98x2.text.find("\nM98 P100 L2\n"), std::string::npos) << r98x2.text;
  EXPECT_NE(
      r98x2.text.find("(truecut rewrite: line 7, the subprogram call M98 P100 L2, written out"),
      std::string::npos)
      << r98x2.text;
}

// The cutter radius is D / 2 of the tool in the spindle: giving the same
// radius by hand changes nothing, a tool of another diameter changes the
// densification of the ball's turn (R per radian of the axis).
TEST(Rewrite, ToolRadiusComesFromTheToolTable) {
  CompensationMatrixData m;
  m.positions_mm = {V(0, 0, 0), V(6, 0, 0)};
  m.vectors_mm = {V(0.02, 0.01, -0.04), V(0.02, 0.01, -0.04)};
  m.valid = {1, 1};
  m.surface_ids = {1, 1};
  RewriteOptions o = options("FIVE", CutType::kBall);
  o.reach_mm = 100;
  const RewriteResult from_table = rewrite_program(kTraori, "five.ngc", m, o);
  ASSERT_EQ(from_table.summary.tool_radii_mm.size(), 1u);
  EXPECT_EQ(from_table.summary.tool_radii_mm[0], (std::pair<int, double>(1, 1.0)));
  RewriteOptions given = o;
  given.tool_radius_mm = 1.0;
  EXPECT_EQ(rewrite_program(kTraori, "five.ngc", m, given).text, from_table.text);
  RewriteOptions larger = o;
  larger.interpreter.tools = ToolTable::parse("T1 P1 D8 Z35\n", "tools.tbl");
  const RewriteResult r4 = rewrite_program(kTraori, "five.ngc", m, larger);
  EXPECT_EQ(r4.summary.tool_radii_mm[0], (std::pair<int, double>(1, 4.0)));
  EXPECT_GT(r4.summary.points_written, from_table.summary.points_written);
}

TEST(Rewrite, ToolMissingFromTheTableOrNotSelectedIsRefusedWithItsLine) {
  RewriteOptions o = options("FACE", CutType::kFace);
  o.reach_mm = 100;
  // The interpreter refuses a tool the table does not hold, at its line.
  EXPECT_EQ(error_of<GcodeError>("G21 G90 G94\n(OPERATION: FACE)\nT3 M6\nG0 X0 Y0 Z1\n"
                                 "G1 Z0 F100\nG1 X1\nM30\n",
                                 o),
            "bad.ngc:3:1: tool T3 is not in the tool table");
  EXPECT_EQ(error_of<GcodeError>("G21 G90 G94\n(OPERATION: FACE)\nG0 X0 Y0 Z1\nG1 Z0 F100\n"
                                 "G1 X1\nM30\n",
                                 o),
            "bad.ngc:4: feed move of operation 'FACE' with no tool in the spindle: the tool radius "
            "comes from the tool table (select the tool with T.. M6 before the move)");
  // G10 L1/L10/L11 edit the table while the program runs: refused by name.
  EXPECT_EQ(error_of<GcodeError>("G21 G90 G94\n(OPERATION: FACE)\nT2 M6\nG10 L1 P2 R2\n"
                                 "G0 X0 Y0 Z1\nG1 Z0 F100\nG1 X1\nM30\n",
                                 o)
                .substr(0, 60),
            "bad.ngc:4: G10 L1/L10/L11 (tool table edit) in the program: ");
  // A ball end mill whose table row has no diameter.
  RewriteOptions ball = options("FACE", CutType::kBall);
  ball.interpreter.tools = ToolTable::parse("T1 P1 D2 Z35\nT2 P2 Z40\n", "tools.tbl");
  EXPECT_EQ(error_of<GcodeError>(kThreeOps, ball).substr(0, 60),
            "bad.ngc:15: tool T2 has diameter 0 in the tool table: a ball");
}

// G95/G96: the mode lines and the F and S words are copied; the densified
// pieces of a move keep its F, which means the same per revolution, and run
// under the same modes (the rewritten program's calls keep G95's context).
TEST(Rewrite, FeedPerRevolutionProgramsKeepTheirModes) {
  const std::string text =
      "G21 G90 G17\n(OPERATION: FACE)\nT2 M6\nG96 S200 D6000 M3\nG95 F0.05\nG0 X-8 Y0 Z1\n"
      "G1 Z0\nG1 X8\nG0 Z5\nM30\n";
  RewriteOptions o = options("FACE", CutType::kFace);
  o.reach_mm = 0.6;
  const RewriteResult r =
      rewrite_program(text, "p.ngc", plane_matrix(-10, 10, -4, 4, 0, 0.5, V(0, 0, 0.05)), o);
  EXPECT_NE(r.text.find("G96 S200 D6000 M3\n"), std::string::npos) << r.text;
  EXPECT_NE(r.text.find("G95 F0.05\n"), std::string::npos) << r.text;
  InterpreterOptions io;
  io.tools = ToolTable::parse(kTools, "tools.tbl");
  const auto prog = Interpreter(io).run_text(r.text, "r.ngc");
  int feeds = 0;
  for (const auto& c : prog.calls) {
    if (const auto* f = std::get_if<SetFeedRate>(&c.op)) {
      EXPECT_TRUE(f->units_per_minute == 0 || f->units_per_minute == 0.05);
    }
    if (std::holds_alternative<StraightFeed>(c.op)) {
      ++feeds;
      EXPECT_EQ(c.context.feed_mode, FeedMode::kUnitsPerRevolution);
    }
  }
  EXPECT_GT(feeds, 10);  // densified
}

TEST(Rewrite, GivenToolRadiusThatDiffersFromTheTableIsRefused) {
  RewriteOptions o = options("FACE", CutType::kFace);
  o.reach_mm = 100;
  o.tool_radius_mm = 1.5;
  EXPECT_EQ(error_of<RewriteError>(kThreeOps, o),
            "the tool radius given (1.5 mm) differs from the tool table's for tool T2 (D 4 mm, "
            "radius 2 mm; first used on bad.ngc:15)");
  o.tool_radius_mm = -1;
  EXPECT_EQ(error_of<std::invalid_argument>(kThreeOps, o), "tool radius must be >= 0 mm");
}

// The rewrite refuses `prog` at `line` with a message containing `words`.
void expect_refused_at(const std::string& prog, const CompensationMatrixData& m,
                       const RewriteOptions& o, int line, const std::string& words) {
  try {
    rewrite_program(prog, "p.ngc", m, o);
    FAIL() << "accepted";
  } catch (const GcodeError& e) {
    EXPECT_EQ(e.where().line, line) << e.what();
    EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
  }
}

// A move far beyond any machine's travel (found by fuzzing: X of 1e31 mm) would be
// densified into more G1 points than an int holds; it is refused with its
// line instead.
TEST(Rewrite, AMoveTooLongToDensifyIsRefusedWithItsLine) {
  const std::string prog =
      "G21 G17 G90 G94\nT1 M6\nG43 H1\nG0 X0 Y0 Z1\n(OPERATION: FAR)\nG1 Z0 F300\n"
      "G1 X10000000000000000000000000000000\nG0 Z10\nM30\n";
  expect_refused_at(prog, plane_matrix(-4, 4, -4, 4, 0, 0.5, V(0.01, 0, 0)),
                    options("FAR", CutType::kPeripheral), 7, "longer than any part's move");
}

// A G5 far longer than any part's move is refused with its line before its
// chords are densified (fuzzing found one taking 12 s to be refused).
TEST(Rewrite, ASplineTooLongToDensifyIsRefusedWithItsLine) {
  const std::string prog =
      "G21 G17 G90 G94\nT1 M6\nG43 H1\nG0 X0 Y0 Z1\n(OPERATION: FAR)\nG1 Z0 F300\n"
      "G5 I0 J2000000 P0 Q-2000000 X10 Y0\nG0 Z10\nM30\n";
  expect_refused_at(prog, plane_matrix(-4, 4, -4, 4, 0, 0.5, V(0.01, 0, 0)),
                    options("FAR", CutType::kPeripheral), 7, "spline would be written as at least");
}

// The limit of G1 points over the whole operation stops the rewrite at the
// line that goes past it: 10 + 10 + 10 mm at 0.5 mm are 20 points each.
TEST(Rewrite, TheLimitOfWrittenPointsNamesTheLineThatPassesIt) {
  const std::string prog =
      "G21 G17 G90 G94\nT1 M6\nG43 H1\nG0 X0 Y0 Z1\n(OPERATION: OP)\nG1 Z0 F300\n"
      "G1 X10\nG1 Y10\nG1 X0\nG0 Z10\nM30\n";
  const auto m = plane_matrix(-4, 14, -4, 14, 0, 0.5, V(0.01, 0, 0));
  RewriteOptions o = options("OP", CutType::kPeripheral);
  o.max_points = 45;
  expect_refused_at(prog, m, o, 9, "more than the limit of 45");
  o.max_points = 1e6;
  EXPECT_NO_THROW(rewrite_program(prog, "p.ngc", m, o));
}

// The motion calls of operation `op`, as rs274 prints them.
std::vector<std::string> motions_of(const std::string& text, const std::string& op) {
  InterpreterOptions io;
  io.tools = ToolTable::parse(kTools, "tools.tbl");
  std::vector<std::string> out;
  for (const CanonCall& c : Interpreter(io).run_text(text, "o.ngc").calls)
    if (c.context.operation == op && is_motion(c.op)) out.push_back(format_rs274(c.op));
  return out;
}

// Another operation's feed right after a corrected point (issue 22, point
// 5): a G1 back to where the original was is written before its line, and
// the other operation makes the very moves it made; an arc keeps its centre.
TEST(Rewrite, TheNextOperationsFeedStartsFromTheOriginalPoint) {
  const std::string head =
      "G21 G17 G90 G94\nT1 M6\nG43 H1\nG0 X0 Y0 Z1\n(OPERATION: OP)\n"
      "G1 Z0 F300\nG1 X10\n(OPERATION: B)\n";
  const auto m = plane_matrix(-4, 24, -10, 14, 0, 0.5, V(0.01, -0.02, 0.005));
  for (const std::string b :
       {"G1 X20\nG1 Y10\n", "G2 X20 Y0 I5 J0\nG1 Y10\n", "G3 X20 Y0 R5 F200\nG1 Y5\n"}) {
    const std::string prog = head + b + "G0 Z10\nM30\n";
    const RewriteResult r = rewrite_program(prog, "p.ngc", m, options("OP", CutType::kPeripheral));
    const std::string first_b = b.substr(0, b.find('\n') + 1);
    EXPECT_NE(r.text.find("\nG1 X10 Y0 Z0\n" + first_b), std::string::npos) << r.text;
    EXPECT_NE(r.text.find("(truecut rewrite: 1 G1 move back from a corrected point"),
              std::string::npos)
        << r.text;
    EXPECT_EQ(r.summary.returns_written, 1);
    std::vector<std::string> want = motions_of(prog, "B");
    want.insert(want.begin(), "STRAIGHT_FEED(10.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)");
    EXPECT_EQ(motions_of(r.text, "B"), want) << r.text;
    // The operation itself still ends on its corrected point.
    const auto op = feeds_of(r.text, "OP");
    ASSERT_FALSE(op.empty());
    EXPECT_NEAR(op.back().x, 10.01, 1e-9);
    EXPECT_NEAR(op.back().y, -0.02, 1e-9);
  }
  // A modal G2 continued without its word would turn into G1 after the G1
  // back: refused by name.
  const std::string modal =
      "G21 G17 G90 G94\nT1 M6\nG43 H1\nG0 X0 Y0 Z1\nG2 X0 Y0 Z0.5 I0 J-1 "
      "F300\n(OPERATION: OP)\nG1 Z0\nG1 X10\n(OPERATION: B)\n"
      "G2 X20 Y0 I5 J0\nG0 Z10\nM30\n";
  EXPECT_NO_THROW(rewrite_program(modal, "p.ngc", m, options("OP", CutType::kPeripheral)));
  const std::string no_word =
      "G21 G17 G90 G94\nT1 M6\nG43 H1\nG0 X0 Y0 Z1\n(OPERATION: OP)\n"
      "G1 Z0 F300\nG2 X10 Y0 I5 J0\n(OPERATION: B)\nX20 Y0 I5 J0\n"
      "G0 Z10\nM30\n";
  expect_refused_at(no_word, m, options("OP", CutType::kPeripheral), 9,
                    "continues a modal G2 without its G word");
}

}  // namespace
}  // namespace truecut::interp
