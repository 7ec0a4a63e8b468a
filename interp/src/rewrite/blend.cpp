// Eqs. 2-5 of the optical-compensation source with the 2-point and 1-point
// fallbacks (docs/rewrite.md, "The blend").
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "truecut/interp/rewrite_blend.hpp"

namespace truecut::interp {

namespace {

constexpr double kCoincident_mm = 1e-9;
constexpr double kDegenerate = 1e-9;  // |V1 x V2| relative to |V1| |V2|

BlendResult one_point(const Eigen::Vector3d& c1) {
  BlendResult r;
  r.correction_mm = c1;
  r.points_used = 1;
  return r;
}

BlendResult two_points(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2,
                       const Eigen::Vector3d& c1, const Eigen::Vector3d& c2,
                       const Eigen::Vector3d& q) {
  const Eigen::Vector3d d = p2 - p1;
  const double len2 = d.squaredNorm();
  if (!(len2 > kCoincident_mm * kCoincident_mm)) return one_point(c1);
  const double t = (q - p1).dot(d) / len2;
  BlendResult r;
  r.a = std::clamp(t, 0.0, 1.0);
  r.clamped = r.a != t;
  r.correction_mm = c1 + r.a * (c2 - c1);
  r.points_used = 2;
  return r;
}

// Barycentric (a, b) of the triangle point nearest to P1 + a V1 + b V2,
// where the triangle is 0 <= b <= a <= 1 (weights 1 - a, a - b, b).
void clamp_to_triangle(const Eigen::Vector3d& v1, const Eigen::Vector3d& v2, double& a, double& b) {
  // Work with the weights on edges e1 = P2 - P1 = V1, e2 = P3 - P1 = V1 + V2:
  // point = P1 + s e1 + t e2 with s = a - b, t = b.
  const Eigen::Vector3d e1 = v1, e2 = v1 + v2;
  const Eigen::Vector3d x = a * v1 + b * v2;  // relative to P1
  double best = std::numeric_limits<double>::infinity(), bs = 0, bt = 0;
  auto consider = [&](double s, double t) {
    const double d = (s * e1 + t * e2 - x).squaredNorm();
    if (d < best) best = d, bs = s, bt = t;
  };
  auto on_segment = [&](const Eigen::Vector3d& from, const Eigen::Vector3d& to, double s0,
                        double t0, double s1, double t1) {
    const Eigen::Vector3d d = to - from;
    const double len2 = d.squaredNorm();
    const double u = len2 > 0 ? std::clamp((x - from).dot(d) / len2, 0.0, 1.0) : 0.0;
    consider(s0 + u * (s1 - s0), t0 + u * (t1 - t0));
  };
  on_segment(Eigen::Vector3d::Zero(), e1, 0, 0, 1, 0);
  on_segment(Eigen::Vector3d::Zero(), e2, 0, 0, 0, 1);
  on_segment(e1, e2, 1, 0, 0, 1);
  a = bs + bt;
  b = bt;
}

}  // namespace

BlendResult blend_compensation(std::span<const Eigen::Vector3d> points,
                               std::span<const Eigen::Vector3d> vectors, const Eigen::Vector3d& q) {
  const size_t n = std::min({points.size(), vectors.size(), size_t{3}});
  if (n == 0) return {};
  if (n == 1) return one_point(vectors[0]);
  if (n == 2) return two_points(points[0], points[1], vectors[0], vectors[1], q);

  const Eigen::Vector3d &p1 = points[0], &p2 = points[1], &p3 = points[2];
  const Eigen::Vector3d &c1 = vectors[0], &c2 = vectors[1], &c3 = vectors[2];
  // Eq. 2: vectors between the compensation points; eq. 3: the normal.
  const Eigen::Vector3d v1 = p2 - p1, v2 = p3 - p2;
  const Eigen::Vector3d normal = v1.cross(v2);
  if (!(normal.norm() > kDegenerate * v1.norm() * v2.norm()) || v1.norm() <= kCoincident_mm ||
      v2.norm() <= kCoincident_mm) {
    // Collinear or coincident: the two nearest distinct points.
    if (v1.norm() > kCoincident_mm) return two_points(p1, p2, c1, c2, q);
    return two_points(p1, p3, c1, c3, q);
  }
  // Eq. 4: q - P1 = a V1 + b V2 + c n, solved with the inverse matrix.
  Eigen::Matrix3d m;
  m.col(0) = v1;
  m.col(1) = v2;
  m.col(2) = normal;
  const Eigen::Vector3d abc = m.inverse() * (q - p1);
  BlendResult r;
  r.a = abc.x();
  r.b = abc.y();
  if (!(r.b >= 0 && r.a >= r.b && r.a <= 1)) {
    clamp_to_triangle(v1, v2, r.a, r.b);
    r.clamped = true;
  }
  // Eq. 5 (without P_T): the blended compensation vector.
  r.correction_mm = c1 + r.a * (c2 - c1) + r.b * (c3 - c2);
  r.points_used = 3;
  return r;
}

}  // namespace truecut::interp
