// How a rigid transform is reported: the 4×4 matrix and, for people, a
// translation in mm and rotation angles in degrees.
#pragma once

#include <Eigen/Geometry>

#include <span>

namespace truecut::offline {

struct RigidTransformReport {
  Eigen::Matrix4d matrix = Eigen::Matrix4d::Identity();  // x' = R·x + t, homogeneous
  Eigen::Vector3d translation_mm = Eigen::Vector3d::Zero();
  // Fixed-axis angles (a, b, c) with R = Rz(c)·Ry(b)·Rx(a), b in [−90°, 90°].
  Eigen::Vector3d rotation_xyz_deg = Eigen::Vector3d::Zero();
  // The same rotation as one turn about a unit axis (angle in [0°, 180°]).
  double rotation_angle_deg = 0.0;
  Eigen::Vector3d rotation_axis = Eigen::Vector3d::UnitZ();
};

RigidTransformReport describe_transform(const Eigen::Isometry3d& transform);

// x ← transform·x for every point.
void transform_points(const Eigen::Isometry3d& transform, std::span<Eigen::Vector3d> points_mm);

}  // namespace truecut::offline
