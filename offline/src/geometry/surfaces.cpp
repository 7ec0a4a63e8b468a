#include "truecut/offline/surfaces.hpp"

#include "truecut/offline/mesh_geometry.hpp"

#include <algorithm>

namespace truecut::offline {

std::vector<std::int32_t> segment_surfaces(const TriangleMesh& mesh, double max_dihedral_deg) {
  const std::size_t n = mesh.triangles.size();
  const std::vector<MeshEdge> edges = mesh_edges(mesh, face_normals(mesh));
  // Adjacency over the smooth edges, as compressed rows.
  std::vector<std::uint32_t> start(n + 1, 0);
  for (const MeshEdge& e : edges) {
    if (e.manifold() && e.dihedral_deg <= max_dihedral_deg) {
      ++start[e.t0 + 1];
      ++start[e.t1 + 1];
    }
  }
  for (std::size_t i = 0; i < n; ++i)
    start[i + 1] += start[i];
  std::vector<std::uint32_t> neighbour(start[n]);
  std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
  for (const MeshEdge& e : edges) {
    if (e.manifold() && e.dihedral_deg <= max_dihedral_deg) {
      neighbour[fill[e.t0]++] = e.t1;
      neighbour[fill[e.t1]++] = e.t0;
    }
  }
  std::vector<std::int32_t> id(n, -1);
  std::vector<std::uint32_t> stack;
  std::int32_t next = 0;
  for (std::size_t seed = 0; seed < n; ++seed) {
    if (id[seed] >= 0) continue;
    id[seed] = next;
    stack.assign(1, static_cast<std::uint32_t>(seed));
    while (!stack.empty()) {
      const std::uint32_t t = stack.back();
      stack.pop_back();
      for (std::uint32_t k = start[t]; k < start[t + 1]; ++k) {
        if (id[neighbour[k]] < 0) {
          id[neighbour[k]] = next;
          stack.push_back(neighbour[k]);
        }
      }
    }
    ++next;
  }
  return id;
}

std::vector<std::uint32_t> triangles_of_surfaces(std::span<const std::int32_t> triangle_surface_ids,
                                                 std::span<const std::int32_t> surfaces) {
  std::vector<std::uint32_t> out;
  for (std::size_t t = 0; t < triangle_surface_ids.size(); ++t) {
    if (std::find(surfaces.begin(), surfaces.end(), triangle_surface_ids[t]) != surfaces.end()) {
      out.push_back(static_cast<std::uint32_t>(t));
    }
  }
  return out;
}

}  // namespace truecut::offline
