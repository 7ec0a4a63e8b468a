// Synthetic nominal parts and scans for the registration and error-vector
// tests: boxes and height-field plates as triangle meshes, and seeded point
// samplings of their surfaces with Gaussian noise.
#pragma once

#include "truecut/offline/mesh.hpp"
#include "truecut/offline/mesh_geometry.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <functional>
#include <map>
#include <random>
#include <tuple>

namespace truecut::offline::test_geo {

// A closed box [lo, lo + size] whose faces are k×k grids of quads, welded
// (edge vertices shared), triangles wound outward.
inline TriangleMesh box(const Eigen::Vector3d& lo, const Eigen::Vector3d& size, int k) {
  TriangleMesh m;
  std::map<std::tuple<int, int, int>, std::uint32_t> index;
  auto vertex = [&](int i, int j, int l) {
    auto [it, fresh] =
        index.try_emplace({i, j, l}, static_cast<std::uint32_t>(m.vertices_mm.size()));
    if (fresh) {
      m.vertices_mm.emplace_back(lo.x() + size.x() * i / k, lo.y() + size.y() * j / k,
                                 lo.z() + size.z() * l / k);
    }
    return it->second;
  };
  // For each axis and side: grid over the two other axes.
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      for (int a = 0; a < k; ++a) {
        for (int b = 0; b < k; ++b) {
          auto at = [&](int da, int db) {
            int c[3];
            c[axis] = side * k;
            c[u] = a + da;
            c[v] = b + db;
            return vertex(c[0], c[1], c[2]);
          };
          const std::uint32_t p00 = at(0, 0), p10 = at(1, 0), p11 = at(1, 1), p01 = at(0, 1);
          // (u × v) = +axis, so this winding faces +axis on side 1.
          if (side == 1) {
            m.triangles.push_back({p00, p10, p11});
            m.triangles.push_back({p00, p11, p01});
          } else {
            m.triangles.push_back({p00, p11, p10});
            m.triangles.push_back({p00, p01, p11});
          }
        }
      }
    }
  }
  return m;
}

// z = height(x, y) over [0, sx] × [0, sy], nx × ny quads, facing +z.
inline TriangleMesh plate(double sx, double sy, int nx, int ny,
                          const std::function<double(double, double)>& height) {
  TriangleMesh m;
  for (int j = 0; j <= ny; ++j) {
    for (int i = 0; i <= nx; ++i) {
      const double x = sx * i / nx, y = sy * j / ny;
      m.vertices_mm.emplace_back(x, y, height(x, y));
    }
  }
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(j * (nx + 1) + i); };
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  }
  return m;
}

// Points uniformly on the mesh surface, density_per_mm2 on average (each
// triangle gets floor or ceil of its expected count), each moved along its
// face normal by N(0, sigma_mm).
inline std::vector<Eigen::Vector3d> sample_surface(const TriangleMesh& m, double density_per_mm2,
                                                   double sigma_mm, std::uint32_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, sigma_mm > 0.0 ? sigma_mm : 1.0);
  const std::vector<Eigen::Vector3d> fn = face_normals(m);
  std::vector<Eigen::Vector3d> out;
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    const Eigen::Vector3d& a = m.vertices_mm[m.triangles[t][0]];
    const Eigen::Vector3d e1 = m.vertices_mm[m.triangles[t][1]] - a;
    const Eigen::Vector3d e2 = m.vertices_mm[m.triangles[t][2]] - a;
    const double expected = 0.5 * e1.cross(e2).norm() * density_per_mm2;
    int count = static_cast<int>(std::floor(expected));
    if (uni(rng) < expected - count) ++count;
    for (int c = 0; c < count; ++c) {
      double u = uni(rng), v = uni(rng);
      if (u + v > 1.0) {
        u = 1.0 - u;
        v = 1.0 - v;
      }
      const double dn = sigma_mm > 0.0 ? noise(rng) : 0.0;
      out.push_back(a + u * e1 + v * e2 + dn * fn[t]);
    }
  }
  return out;
}

inline Eigen::Isometry3d rigid(const Eigen::Vector3d& axis, double angle_deg,
                               const Eigen::Vector3d& translation_mm) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(angle_deg * M_PI / 180.0, axis.normalized()).toRotationMatrix();
  T.translation() = translation_mm;
  return T;
}

}  // namespace truecut::offline::test_geo
