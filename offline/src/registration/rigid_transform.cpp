#include "truecut/offline/rigid_transform.hpp"

#include <cmath>

namespace truecut::offline {

namespace {
constexpr double kDeg = 180.0 / M_PI;
}

RigidTransformReport describe_transform(const Eigen::Isometry3d& transform) {
  RigidTransformReport r;
  r.matrix = transform.matrix();
  r.translation_mm = transform.translation();
  const Eigen::Matrix3d R = transform.linear();
  const double b = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
  double a, c;
  if (std::abs(R(2, 0)) < 1.0 - 1e-12) {
    a = std::atan2(R(2, 1), R(2, 2));
    c = std::atan2(R(1, 0), R(0, 0));
  } else {  // gimbal lock: only a − c (or a + c) is defined; put it all in a
    a = std::atan2(-R(1, 2), R(1, 1));
    c = 0.0;
  }
  r.rotation_xyz_deg = Eigen::Vector3d(a, b, c) * kDeg;
  const Eigen::AngleAxisd aa(R);
  r.rotation_angle_deg = aa.angle() * kDeg;
  r.rotation_axis = aa.angle() > 0.0 ? aa.axis() : Eigen::Vector3d::UnitZ();
  return r;
}

void transform_points(const Eigen::Isometry3d& transform, std::span<Eigen::Vector3d> points_mm) {
  for (Eigen::Vector3d& p : points_mm)
    p = transform * p;
}

}  // namespace truecut::offline
