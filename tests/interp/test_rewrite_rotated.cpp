// truecut::interp::rewrite_program on a program in a rotated coordinate
// system (G10 L2 R) with a G5x origin and a G52 offset: the corrections are
// vectors of the workpiece frame, so in the program's own (turned) frame
// each point moves by the vector turned back, and arcs stay arcs of the
// turned plane. The expected path and the frames are computed here from
// the offsets written in the program, not through the rewriter's helpers.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "rewrite_test_util.hpp"
#include "truecut/interp/rewrite.hpp"

namespace truecut::interp {
namespace {

using V = Eigen::Vector3d;

constexpr double kRotationDeg = 30.0;
const V kG5x(20.0, -10.0, 0.0);
const V kG52(1.0, 2.0, 0.0);

const char* kProgram =
    "G21 G17 G90 G94\n"
    "T2 M6\n"
    "G43 H2\n"
    "G10 L2 P1 X20 Y-10 Z0 R30\n"
    "G54\n"
    "G52 X1 Y2\n"
    "(OPERATION: FACE)\n"
    "G0 X-8 Y-2 Z5\n"
    "G1 Z0 F200\n"
    "G1 X8\n"
    "G3 X8 Y2 I0 J2\n"
    "G1 X-4\n"
    "G18 G2 X-2 Z0 I1 K0\n"
    "G17\n"
    "G0 Z5\n"
    "M30\n";

Eigen::Matrix3d turn() {
  return Eigen::AngleAxisd(kRotationDeg * std::numbers::pi / 180.0, V::UnitZ()).toRotationMatrix();
}

double distance_to_segment(const V& p, const V& a, const V& b) {
  const V d = b - a;
  const double t = std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
  return (a + t * d - p).norm();
}

// Distance from p to the circle of radius r about c in the plane through c
// spanned by axes u and v.
double distance_to_circle(const V& p, const V& c, const V& u, const V& v, double r) {
  const V d = p - c;
  const double in_u = d.dot(u), in_v = d.dot(v);
  const double off = (d - in_u * u - in_v * v).norm();
  return std::hypot(std::hypot(in_u, in_v) - r, off);
}

TEST(RewriteRotated, CorrectionsAreTurnedIntoTheRotatedProgramFrame) {
  const V shift_mm(0.03, -0.02, 0.01);  // workpiece frame
  const CompensationMatrixData m = testing::plane_matrix(-40, 40, -40, 40, 0, 1.0, shift_mm);
  RewriteOptions o;
  o.operation = "FACE";
  o.type = CutType::kFace;
  o.interpreter.tools = ToolTable::parse("T2 P2 D4 Z40\n", "tools.tbl");
  o.reach_mm = 100;  // every point compensated
  o.decimals = 6;
  const RewriteResult r = rewrite_program(kProgram, "rot.ngc", m, o);
  EXPECT_GT(r.summary.points_compensated, 0);

  // The rewritten program keeps the rotation and the offsets; its feeds are
  // program coordinates of the turned frame.
  InterpreterOptions io = o.interpreter;
  const CanonProgram out = Interpreter(io).run_text(r.text, "out.ngc");
  const Eigen::Matrix3d rot = turn();
  const V shift_in_program = rot.transpose() * shift_mm;
  int on_xy_arc = 0, on_xz_arc = 0, feeds = 0;
  for (const CanonCall& c : out.calls) {
    if (c.context.operation != "FACE") continue;
    const auto* f = std::get_if<StraightFeed>(&c.op);
    ASSERT_EQ(std::get_if<ArcFeed>(&c.op), nullptr) << "arcs are written as densified lines";
    if (f == nullptr) continue;
    ++feeds;
    EXPECT_DOUBLE_EQ(c.context.xy_rotation_deg, kRotationDeg);
    // Where the machine goes (workpiece frame), independently of the
    // interpreter: G5x + rotation × (program + G52).
    const V program(f->end.x, f->end.y, f->end.z);
    const V machine = kG5x + rot * (program + kG52);
    // Without the correction, back in the frame the program was written in.
    const V q = rot.transpose() * (machine - shift_mm - kG5x) - kG52;
    EXPECT_LE((program - shift_in_program - q).norm(), 1e-12);
    const double d_lines = std::min({distance_to_segment(q, V(-8, -2, 5), V(-8, -2, 0)),
                                     distance_to_segment(q, V(-8, -2, 0), V(8, -2, 0)),
                                     distance_to_segment(q, V(8, 2, 0), V(-4, 2, 0))});
    const double d_xy =
        q.x() >= 8.0 - 1e-9 ? distance_to_circle(q, V(8, 0, 0), V::UnitX(), V::UnitY(), 2.0) : 1e9;
    const double d_xz = distance_to_circle(q, V(-3, 2, 0), V::UnitX(), V::UnitZ(), 1.0);
    const double d = std::min({d_lines, d_xy, d_xz});
    EXPECT_LE(d, 1e-5) << q.transpose();
    if (d_xy < 1e-5 && std::abs(q.y()) < 1.9) ++on_xy_arc;
    if (d_xz < 1e-5 && std::abs(q.z()) > 0.5) {
      ++on_xz_arc;
      // G2 in G18 is clockwise in the (Z, X) plane: from about
      // X-3 it passes through Z-1.
      EXPECT_LT(q.z(), 0.0) << q.transpose();
    }
  }
  EXPECT_GT(feeds, 20);
  EXPECT_GE(on_xy_arc, 5);
  EXPECT_GE(on_xz_arc, 2);
}

}  // namespace
}  // namespace truecut::interp
