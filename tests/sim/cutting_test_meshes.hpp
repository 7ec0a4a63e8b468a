// Flat meshes for the cutting tests.
#pragma once

#include <Eigen/Core>

#include <cstdint>

#include "truecut/offline/mesh.hpp"

namespace truecut::sim::test {

// A gridded rectangle origin + [0, nu·cell]·u + [0, nv·cell]·v, normal u × v.
inline offline::TriangleMesh grid(const Eigen::Vector3d& origin, const Eigen::Vector3d& u,
                                  const Eigen::Vector3d& v, int nu, int nv, double cell) {
  offline::TriangleMesh m;
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i <= nu; ++i)
      m.vertices_mm.push_back(origin + (i * cell) * u + (j * cell) * v);
  auto id = [&](int i, int j) { return std::uint32_t(j * (nu + 1) + i); };
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return m;
}

}  // namespace truecut::sim::test
