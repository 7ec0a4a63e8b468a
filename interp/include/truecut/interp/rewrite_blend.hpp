// The blend of the optical-compensation source (Denkena et al., eqs. 2-5):
// the compensation vector at a tool point from the compensation vectors of
// its nearest compensation points. docs/rewrite.md gives the equations.
#pragma once

#include <Eigen/Core>
#include <span>

namespace truecut::interp {

struct BlendResult {
  Eigen::Vector3d correction_mm = Eigen::Vector3d::Zero();
  // How the vector was formed: 3 = triangle (eqs. 2-5), 2 = linear between
  // two points, 1 = the nearest point's vector, 0 = none (no points).
  int points_used = 0;
  // Triangle weights of P_corr = P_T + C1 + a (C2 - C1) + b (C3 - C2)
  // (a = the line parameter t for 2 points), after clamping to the triangle.
  double a = 0, b = 0;
  bool clamped = false;  // the query's foot lay outside the triangle (segment)
};

// `points` (at most 3 used, nearest first) and their `vectors`. The query
// point is projected along the triangle normal into the triangle's plane
// (eq. 4, solved with the inverse of [V1 V2 n]); a foot outside the triangle
// is moved to the nearest point of the triangle, so the result never leaves
// the convex hull of the vectors. A degenerate triangle (collinear or
// coincident points, |V1 x V2| <= 1e-9 |V1| |V2|) falls back to the two
// nearest distinct points, coincident ones to the nearest point's vector.
BlendResult blend_compensation(std::span<const Eigen::Vector3d> points,
                               std::span<const Eigen::Vector3d> vectors,
                               const Eigen::Vector3d& query_mm);

}  // namespace truecut::interp
