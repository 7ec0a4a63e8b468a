// Per-triangle and per-edge geometry of a triangle mesh: face normals and
// areas, vertex normals, and the edges with their dihedral angles (what the
// surface segmentation, the ray method's edge test and the sphere method's
// plane clusters are built on).
#pragma once

#include "truecut/offline/mesh.hpp"

#include <Eigen/Geometry>

#include <cstdint>
#include <vector>

namespace truecut::offline {

inline constexpr std::uint32_t kNoTriangle = 0xffffffffu;

// Unit normals by the right-hand rule over (a, b, c); zero for a degenerate
// triangle.
std::vector<Eigen::Vector3d> face_normals(const TriangleMesh& mesh);
std::vector<double> face_areas_mm2(const TriangleMesh& mesh);

// Angle-weighted pseudo-normals (each incident triangle weighted by its
// corner angle at the vertex), so the result does not depend on how a face is
// split into triangles. Zero for a vertex no triangle uses.
std::vector<Eigen::Vector3d> vertex_normals(const TriangleMesh& mesh);

struct MeshEdge {
  std::uint32_t v0 = 0, v1 = 0;  // v0 < v1
  std::uint32_t t0 = kNoTriangle;
  std::uint32_t t1 = kNoTriangle;    // kNoTriangle on a boundary edge
  std::uint32_t triangle_count = 0;  // 1 boundary, 2 manifold, > 2 non-manifold
  // Angle between the face normals of t0 and t1 (0 = flat, 90 = square
  // edge); 180 for boundary and non-manifold edges.
  double dihedral_deg = 0.0;

  bool manifold() const { return triangle_count == 2; }
};

// Each undirected edge once, ordered by (v0, v1).
std::vector<MeshEdge> mesh_edges(const TriangleMesh& mesh,
                                 const std::vector<Eigen::Vector3d>& face_normals);

// Closest point to p on triangle (a, b, c), exact in double.
Eigen::Vector3d closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                          const Eigen::Vector3d& b, const Eigen::Vector3d& c);

// Closest point to p on the segment from a to b.
Eigen::Vector3d closest_point_on_segment(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                         const Eigen::Vector3d& b);

}  // namespace truecut::offline
