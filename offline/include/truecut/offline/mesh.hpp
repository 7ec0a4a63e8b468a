// In-memory triangle meshes and point clouds, as read from scans and nominal
// models. Coordinates are in mm. Vertices are stored contiguously (xyz, xyz,
// ...) so a whole mesh can be viewed as an Eigen 3×N matrix without copying
// (see as_matrix()).
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <vector>

namespace truecut::offline {

using Triangle = std::array<std::uint32_t, 3>;

struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices_mm;
  std::vector<Triangle> triangles;
  // Unit per-vertex normals; empty when the file had none, else one per vertex.
  std::vector<Eigen::Vector3d> normals;

  bool has_normals() const { return !normals.empty(); }
};

struct PointCloud {
  std::vector<Eigen::Vector3d> points_mm;
  // Empty when the file had none, else one per point.
  std::vector<Eigen::Vector3d> normals;

  bool has_normals() const { return !normals.empty(); }
};

// A 3×N column view of a point array (Eigen::Vector3d is unaligned and packed).
inline Eigen::Map<const Eigen::Matrix3Xd> as_matrix(const std::vector<Eigen::Vector3d>& v) {
  return {v.empty() ? nullptr : v.front().data(), 3, static_cast<Eigen::Index>(v.size())};
}
inline Eigen::Map<Eigen::Matrix3Xd> as_matrix(std::vector<Eigen::Vector3d>& v) {
  return {v.empty() ? nullptr : v.front().data(), 3, static_cast<Eigen::Index>(v.size())};
}

}  // namespace truecut::offline
