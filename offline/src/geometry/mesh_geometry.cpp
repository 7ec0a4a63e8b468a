#include "truecut/offline/mesh_geometry.hpp"

#include "geometry/half_edge_order.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace truecut::offline {

std::vector<Eigen::Vector3d> face_normals(const TriangleMesh& mesh) {
  std::vector<Eigen::Vector3d> n(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& [a, b, c] = mesh.triangles[t];
    const Eigen::Vector3d& pa = mesh.vertices_mm[a];
    const Eigen::Vector3d cross = (mesh.vertices_mm[b] - pa).cross(mesh.vertices_mm[c] - pa);
    const double len = cross.norm();
    n[t] = len > 0.0 ? Eigen::Vector3d(cross / len) : Eigen::Vector3d::Zero();
  }
  return n;
}

std::vector<double> face_areas_mm2(const TriangleMesh& mesh) {
  std::vector<double> area(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& [a, b, c] = mesh.triangles[t];
    const Eigen::Vector3d& pa = mesh.vertices_mm[a];
    area[t] = 0.5 * (mesh.vertices_mm[b] - pa).cross(mesh.vertices_mm[c] - pa).norm();
  }
  return area;
}

namespace {

double corner_angle(const Eigen::Vector3d& at, const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
  const Eigen::Vector3d u = p - at, v = q - at;
  return std::atan2(u.cross(v).norm(), u.dot(v));
}

}  // namespace

std::vector<Eigen::Vector3d> vertex_normals(const TriangleMesh& mesh) {
  std::vector<Eigen::Vector3d> sum(mesh.vertices_mm.size(), Eigen::Vector3d::Zero());
  const std::vector<Eigen::Vector3d> fn = face_normals(mesh);
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle& tri = mesh.triangles[t];
    for (int k = 0; k < 3; ++k) {
      const auto& at = mesh.vertices_mm[tri[k]];
      const auto& p = mesh.vertices_mm[tri[(k + 1) % 3]];
      const auto& q = mesh.vertices_mm[tri[(k + 2) % 3]];
      sum[tri[k]] += corner_angle(at, p, q) * fn[t];
    }
  }
  for (Eigen::Vector3d& n : sum) {
    const double len = n.norm();
    n = len > 0.0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
  }
  return sum;
}

std::vector<MeshEdge> mesh_edges(const TriangleMesh& mesh,
                                 const std::vector<Eigen::Vector3d>& normals) {
  struct HalfEdge {
    std::uint32_t v0, v1, t;
  };
  std::vector<HalfEdge> half;
  half.reserve(3 * mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle& tri = mesh.triangles[t];
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = tri[k], b = tri[(k + 1) % 3];
      half.push_back({std::min(a, b), std::max(a, b), static_cast<std::uint32_t>(t)});
    }
  }
  geometry::sort_half_edges(
      half, [](const HalfEdge& h) { return h.v0; },
      [](const HalfEdge& x, const HalfEdge& y) {
        return std::tie(x.v0, x.v1, x.t) < std::tie(y.v0, y.v1, y.t);
      });
  std::vector<MeshEdge> edges;
  edges.reserve(half.size() / 2 + 1);
  for (std::size_t i = 0; i < half.size();) {
    std::size_t j = i;
    while (j < half.size() && half[j].v0 == half[i].v0 && half[j].v1 == half[i].v1)
      ++j;
    MeshEdge e;
    e.v0 = half[i].v0;
    e.v1 = half[i].v1;
    e.t0 = half[i].t;
    e.triangle_count = static_cast<std::uint32_t>(j - i);
    if (e.triangle_count >= 2) e.t1 = half[i + 1].t;
    if (e.manifold()) {
      const double c = std::clamp(normals[e.t0].dot(normals[e.t1]), -1.0, 1.0);
      const double s = normals[e.t0].cross(normals[e.t1]).norm();
      e.dihedral_deg = std::atan2(s, c) * 180.0 / M_PI;
    } else {
      e.dihedral_deg = 180.0;
    }
    edges.push_back(e);
    i = j;
  }
  return edges;
}

Eigen::Vector3d closest_point_on_segment(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                         const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double len2 = ab.squaredNorm();
  if (len2 == 0.0) return a;
  const double s = std::clamp((p - a).dot(ab) / len2, 0.0, 1.0);
  return a + s * ab;
}

// Region by region (vertex, edge or face) as in Ericson, "Real-Time
// Collision Detection", 5.1.5.
Eigen::Vector3d closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                          const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return a + (d1 / (d1 - d3)) * ab;
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return a + (d2 / (d2 - d6)) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  }
  const double denom = va + vb + vc;
  if (denom == 0.0) return closest_point_on_segment(p, a, b);  // degenerate triangle
  const double v = vb / denom, w = vc / denom;
  return a + v * ab + w * ac;
}

}  // namespace truecut::offline
