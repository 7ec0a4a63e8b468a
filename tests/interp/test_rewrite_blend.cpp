// The blend of the optical-compensation source (eqs. 2-5) and the
// compensation matrix reader, on hand-computed cases.
#include <gtest/gtest.h>

#include <vector>

#include "truecut/interp/rewrite_blend.hpp"
#include "truecut/interp/rewrite_matrix.hpp"

namespace truecut::interp {
namespace {

using V = Eigen::Vector3d;

BlendResult blend(std::vector<V> p, std::vector<V> c, V q) {
  return blend_compensation(p, c, q);
}

TEST(RewriteBlend, NoPointsGiveNoCorrection) {
  const BlendResult r = blend({}, {}, V(1, 2, 3));
  EXPECT_EQ(r.points_used, 0);
  EXPECT_EQ(r.correction_mm, V::Zero());
}

TEST(RewriteBlend, OnePointGivesItsVector) {
  const BlendResult r = blend({V(5, 5, 5)}, {V(0.01, -0.02, 0.03)}, V(0, 0, 0));
  EXPECT_EQ(r.points_used, 1);
  EXPECT_EQ(r.correction_mm, V(0.01, -0.02, 0.03));
}

TEST(RewriteBlend, TwoPointsBlendLinearlyAlongTheirLine) {
  // P1 (0,0,0) C1 (0,0,0.1); P2 (2,0,0) C2 (0,0,0.3). Q projects to x = 0.5:
  // t = 0.25, C = 0.1 + 0.25 * 0.2 = 0.15 (the offset of Q off the line does
  // not matter).
  const BlendResult r =
      blend({V(0, 0, 0), V(2, 0, 0)}, {V(0, 0, 0.1), V(0, 0, 0.3)}, V(0.5, 7, -3));
  EXPECT_EQ(r.points_used, 2);
  EXPECT_DOUBLE_EQ(r.a, 0.25);
  EXPECT_NEAR(r.correction_mm.z(), 0.15, 1e-15);
  EXPECT_FALSE(r.clamped);
  // Beyond P2 the line parameter is clamped: P2's vector.
  const BlendResult far = blend({V(0, 0, 0), V(2, 0, 0)}, {V(0, 0, 0.1), V(0, 0, 0.3)}, V(5, 0, 0));
  EXPECT_TRUE(far.clamped);
  EXPECT_NEAR(far.correction_mm.z(), 0.3, 1e-15);
}

TEST(RewriteBlend, ThreePointsFollowEquationsTwoToFive) {
  // V1 = P2 - P1 = (1,0,0), V2 = P3 - P2 = (0,1,0), n = (0,0,1). Q - P1 =
  // (0.75, 0.25, 5) = 0.75 V1 + 0.25 V2 + 5 n: a = 0.75, b = 0.25;
  // C = C1 + a (C2 - C1) + b (C3 - C2) = 1 + 0.75 * 1 + 0.25 * 2 = 2.25.
  const BlendResult r = blend({V(0, 0, 0), V(1, 0, 0), V(1, 1, 0)},
                              {V(0, 0, 1), V(0, 0, 2), V(0, 0, 4)}, V(0.75, 0.25, 5));
  EXPECT_EQ(r.points_used, 3);
  EXPECT_NEAR(r.a, 0.75, 1e-15);
  EXPECT_NEAR(r.b, 0.25, 1e-15);
  EXPECT_NEAR(r.correction_mm.z(), 2.25, 1e-14);
  EXPECT_FALSE(r.clamped);
}

TEST(RewriteBlend, ThreePointsOnATiltedTriangle) {
  // P1 (1,1,1), V1 = (2,0,2), V2 = (0,3,0): P2 (3,1,3), P3 (3,4,3);
  // n = V1 x V2 = (-6,0,6). Q = P1 + 0.5 V1 + 0.2 V2 + 0.1 n = (1.4,1.6,2.6).
  // C1 (0.1,0,0), C2 (0,0.2,0), C3 (0,0,0.4):
  // C = C1 + 0.5 (C2 - C1) + 0.2 (C3 - C2) = (0.05, 0.06, 0.08).
  const BlendResult r = blend({V(1, 1, 1), V(3, 1, 3), V(3, 4, 3)},
                              {V(0.1, 0, 0), V(0, 0.2, 0), V(0, 0, 0.4)}, V(1.4, 1.6, 2.6));
  EXPECT_EQ(r.points_used, 3);
  EXPECT_NEAR(r.a, 0.5, 1e-14);
  EXPECT_NEAR(r.b, 0.2, 1e-14);
  EXPECT_NEAR((r.correction_mm - V(0.05, 0.06, 0.08)).norm(), 0, 1e-15);
}

TEST(RewriteBlend, FootOutsideTheTriangleIsClampedToIt) {
  // Same triangle as above (legs along x and y); Q beyond the hypotenuse
  // P1-P3 side... at (2, 0.5): nearest triangle point is on edge P2-P3 at
  // (1, 0.5): a = 1, b = 0.5, C = 1 + 1 + 0.5 * 2 = 3.
  const BlendResult r = blend({V(0, 0, 0), V(1, 0, 0), V(1, 1, 0)},
                              {V(0, 0, 1), V(0, 0, 2), V(0, 0, 4)}, V(2, 0.5, 0));
  EXPECT_TRUE(r.clamped);
  EXPECT_NEAR(r.a, 1.0, 1e-15);
  EXPECT_NEAR(r.b, 0.5, 1e-15);
  EXPECT_NEAR(r.correction_mm.z(), 3.0, 1e-14);
  // Never beyond the largest vector.
  for (double x = -3; x <= 3; x += 0.5)
    for (double y = -3; y <= 3; y += 0.5) {
      const BlendResult s = blend({V(0, 0, 0), V(1, 0, 0), V(1, 1, 0)},
                                  {V(0, 0, 1), V(0, 0, 2), V(0, 0, 4)}, V(x, y, 1));
      EXPECT_GE(s.correction_mm.z(), 1 - 1e-12);
      EXPECT_LE(s.correction_mm.z(), 4 + 1e-12);
    }
}

TEST(RewriteBlend, DegenerateTrianglesFallBack) {
  // Collinear: linear between the two nearest (P1, P2).
  const BlendResult line = blend({V(0, 0, 0), V(1, 0, 0), V(2, 0, 0)},
                                 {V(0, 0, 1), V(0, 0, 3), V(0, 0, 100)}, V(0.5, 1, 0));
  EXPECT_EQ(line.points_used, 2);
  EXPECT_NEAR(line.correction_mm.z(), 2.0, 1e-15);
  // P1 and P2 coincide: linear between P1 and P3.
  const BlendResult twin =
      blend({V(0, 0, 0), V(0, 0, 0), V(0, 4, 0)}, {V(0, 0, 1), V(0, 0, 9), V(0, 0, 5)}, V(0, 1, 0));
  EXPECT_EQ(twin.points_used, 2);
  EXPECT_NEAR(twin.correction_mm.z(), 2.0, 1e-15);
  // All three coincide: the nearest point's vector.
  const BlendResult one =
      blend({V(1, 1, 1), V(1, 1, 1), V(1, 1, 1)}, {V(0, 0, 1), V(0, 0, 9), V(0, 0, 5)}, V(0, 1, 0));
  EXPECT_EQ(one.points_used, 1);
  EXPECT_EQ(one.correction_mm, V(0, 0, 1));
}

TEST(RewriteMatrix, ReadsTheDocumentedFormat) {
  const std::string text =
      "# truecut compensation matrix v1\r\n# frame: workpiece\r\n# units: mm\r\n"
      "# dx,dy,dz: compensation vector = -(measured - nominal); 0 where valid = 0\r\n"
      "x,y,z,dx,dy,dz,valid,surface_id\r\n1,2,3,0,0,-0.125,1,4\r\n"
      "0.1,-0.2,0.001,0.03,0,0,1,7\r\n5,5,5,0,0,0,0,4\r\n";
  const CompensationMatrixData m = parse_compensation_matrix(text, "m.csv");
  ASSERT_EQ(m.size(), 3u);
  EXPECT_EQ(m.positions_mm[1], V(0.1, -0.2, 0.001));
  EXPECT_EQ(m.vectors_mm[0], V(0, 0, -0.125));
  EXPECT_EQ(m.valid, (std::vector<std::uint8_t>{1, 1, 0}));
  EXPECT_EQ(m.surface_ids, (std::vector<std::int32_t>{4, 7, 4}));
  // Columns by name, in any order; valid and surface_id optional.
  const auto n = parse_compensation_matrix("dz,dy,dx,z,y,x\n3,2,1,0.5,0.25,0.125\n", "n.csv");
  EXPECT_EQ(n.positions_mm[0], V(0.125, 0.25, 0.5));
  EXPECT_EQ(n.vectors_mm[0], V(1, 2, 3));
  EXPECT_EQ(n.valid[0], 1);
}

std::string matrix_error(const std::string& text) {
  try {
    parse_compensation_matrix(text, "bad.csv");
  } catch (const RewriteError& e) {
    return e.what();
  }
  return "no error";
}

TEST(RewriteMatrix, BadInputNamesFileAndLine) {
  EXPECT_EQ(matrix_error("# c\nx,y,z,dx,dy\n1,2,3,4,5\n"),
            "bad.csv:2: header has no column 'dz' (expected x,y,z,dx,dy,dz[,valid][,surface_id])");
  EXPECT_EQ(matrix_error("x,y,z,dx,dy,dz\n1,2,3,0,0,0\n1,2,3,nan,0,0\n"),
            "bad.csv:3: dx is not finite (nan)");
  EXPECT_EQ(matrix_error("x,y,z,dx,dy,dz\n1,2,3,0,0,inf\n"), "bad.csv:2: dz is not finite (inf)");
  EXPECT_EQ(matrix_error("x,y,z,dx,dy,dz\n1,2,3,0,0\n"), "bad.csv:2: 5 fields, the header has 6");
  EXPECT_EQ(matrix_error("x,y,z,dx,dy,dz\n1,2,3,0,0,1mm\n"), "bad.csv:2: dz '1mm' is not a number");
  EXPECT_EQ(matrix_error("x,y,z,dx,dy,dz,valid\n1,2,3,0,0,1,2\n"),
            "bad.csv:2: valid must be 0 or 1");
  EXPECT_EQ(matrix_error("# only comments\n"),
            "bad.csv: no header line x,y,z,dx,dy,dz (empty compensation matrix)");
  EXPECT_EQ(matrix_error("x,y,z,dx,dy,dz\n"), "bad.csv: no compensation points");
  // Beyond any machine or any compensation: a unit or writing mistake.
  EXPECT_EQ(matrix_error("x,y,z,dx,dy,dz\n1e300,0,0,0,0,0.01\n"),
            "bad.csv:2: x 1e300 mm is outside ±1e5 mm (no machine is larger than 100 m); check "
            "the unit");
  EXPECT_EQ(matrix_error("x,y,z,dx,dy,dz\n0,0,0,0,0,-2000\n"),
            "bad.csv:2: dz -2000 mm is outside ±1e3 mm (no compensation of a finished part is a "
            "metre); check the unit");
  // One position, two vectors: which one the blend met first would decide.
  EXPECT_EQ(matrix_error("x,y,z,dx,dy,dz\n1,2,3,0,0,0.01\n4,5,6,0,0,0\n1,2,3,0,0,0.02\n"),
            "bad.csv:4: the point at x y z of line 2 is given again with another vector, surface "
            "or validity: which one holds?");
  EXPECT_EQ(matrix_error("x,y,z,dx,dy,dz\n1,2,3,0,0,0.01\n1,2,3,0,0,0.01\n"), "no error");
}

}  // namespace
}  // namespace truecut::interp
