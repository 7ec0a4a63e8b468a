// Simple meshes for the scanner and CMM tests: boxes, planes and unions.
#pragma once

#include <Eigen/Geometry>

#include <cstdint>
#include <vector>

#include "truecut/offline/mesh.hpp"

namespace truecut::test {

// Closed axis-aligned box, outward winding; surface ids 0 −x, 1 +x, 2 −y,
// 3 +y, 4 −z, 5 +z (two triangles each, in that order).
inline offline::TriangleMesh box_mesh(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                                      std::vector<std::int32_t>* surface_ids = nullptr) {
  offline::TriangleMesh m;
  for (int i = 0; i < 8; ++i)
    m.vertices_mm.emplace_back((i & 1) ? hi.x() : lo.x(), (i & 2) ? hi.y() : lo.y(),
                               (i & 4) ? hi.z() : lo.z());
  // Corner index = x + 2y + 4z; each quad listed counter-clockwise seen from outside.
  const std::uint32_t quads[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                     {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  for (int f = 0; f < 6; ++f) {
    const auto& q = quads[f];
    m.triangles.push_back({q[0], q[1], q[2]});
    m.triangles.push_back({q[0], q[2], q[3]});
    if (surface_ids) surface_ids->insert(surface_ids->end(), 2, f);
  }
  return m;
}

// Appends b to a (no welding).
inline void append_mesh(offline::TriangleMesh& a, const offline::TriangleMesh& b) {
  const auto base = static_cast<std::uint32_t>(a.vertices_mm.size());
  a.vertices_mm.insert(a.vertices_mm.end(), b.vertices_mm.begin(), b.vertices_mm.end());
  for (const auto& t : b.triangles)
    a.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
}

// A square of half-size `half_mm` through `centre_mm` with unit normal `n`
// (winding follows n).
inline offline::TriangleMesh plane_mesh(const Eigen::Vector3d& centre_mm, const Eigen::Vector3d& n,
                                        double half_mm) {
  const Eigen::Vector3d helper =
      std::abs(n.z()) < 0.9 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d u = helper.cross(n).normalized();
  const Eigen::Vector3d v = n.cross(u);
  offline::TriangleMesh m;
  m.vertices_mm = {centre_mm - half_mm * u - half_mm * v, centre_mm + half_mm * u - half_mm * v,
                   centre_mm + half_mm * u + half_mm * v, centre_mm - half_mm * u + half_mm * v};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

}  // namespace truecut::test
