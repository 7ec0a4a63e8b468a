#include "truecut/offline/mesh_topology.hpp"

#include "geometry/half_edge_order.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <queue>
#include <vector>

#include <Eigen/Geometry>

namespace truecut::offline {

namespace {

struct HalfEdge {
  std::uint64_t key;  // (lower vertex << 32) | higher vertex
  std::uint32_t triangle;
  bool forward;  // the triangle runs lower → higher
};

// Two triangles across a two-triangle edge; same: they traverse it the same
// way (their windings disagree).
struct Link {
  std::uint32_t other;
  bool same;
};

MeshTopology analyse(const TriangleMesh& mesh, std::vector<std::uint8_t>* flip) {
  const std::size_t nt = mesh.triangles.size();
  std::vector<HalfEdge> half;
  half.reserve(3 * nt);
  for (std::size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = mesh.triangles[t][k], b = mesh.triangles[t][(k + 1) % 3];
      const std::uint32_t lo = std::min(a, b), hi = std::max(a, b);
      half.push_back({(std::uint64_t{lo} << 32) | hi, static_cast<std::uint32_t>(t), a < b});
    }
  geometry::sort_half_edges(
      half, [](const HalfEdge& h) { return static_cast<std::uint32_t>(h.key >> 32); },
      [](const HalfEdge& x, const HalfEdge& y) {
        return x.key != y.key ? x.key < y.key : x.triangle < y.triangle;
      });

  MeshTopology m;
  // At most one link per half-edge, so three per triangle.
  struct Links {
    std::array<Link, 3> link;
    std::uint8_t count = 0;
    void add(const Link& l) { link[count++] = l; }
    const Link* begin() const { return link.data(); }
    const Link* end() const { return link.data() + count; }
  };
  std::vector<Links> links(nt);
  std::vector<std::uint8_t> open(nt, 0);
  for (std::size_t i = 0; i < half.size();) {
    std::size_t j = i;
    while (j < half.size() && half[j].key == half[i].key)
      ++j;
    ++m.edges;
    const std::size_t uses = j - i;
    if (uses == 1) {
      ++m.boundary_edges;
      open[half[i].triangle] = 1;
    } else if (uses > 2) {
      ++m.nonmanifold_edges;
      for (std::size_t k = i; k < j; ++k)
        open[half[k].triangle] = 1;
    } else {
      const bool same = half[i].forward == half[i + 1].forward;
      if (same) ++m.inconsistent_edges;
      links[half[i].triangle].add({half[i + 1].triangle, same});
      links[half[i + 1].triangle].add({half[i].triangle, same});
    }
    i = j;
  }

  // Each shell: a consistent winding relative to its first triangle, then
  // the choice of the two that the shell's kind asks for.
  std::vector<std::int8_t> turn(nt, -1);  // 1: against the shell's first triangle
  std::vector<std::uint32_t> shell;
  for (std::size_t start = 0; start < nt; ++start) {
    if (turn[start] >= 0) continue;
    ++m.shells;
    shell.clear();
    bool orientable = true, is_open = false;
    turn[start] = 0;
    std::queue<std::uint32_t> next;
    next.push(static_cast<std::uint32_t>(start));
    while (!next.empty()) {
      const std::uint32_t t = next.front();
      next.pop();
      shell.push_back(t);
      is_open = is_open || open[t];
      for (const Link& l : links[t]) {
        const std::int8_t want = static_cast<std::int8_t>(turn[t] ^ (l.same ? 1 : 0));
        if (turn[l.other] < 0) {
          turn[l.other] = want;
          next.push(l.other);
        } else if (turn[l.other] != want) {
          orientable = false;
        }
      }
    }
    if (is_open) ++m.open_shells;
    if (!orientable) {
      ++m.nonorientable_shells;
      continue;
    }
    std::size_t turned = 0;
    for (std::uint32_t t : shell)
      turned += turn[t];
    bool turn_all;  // turn the shell's first triangle (and what follows it) round
    if (!is_open) {
      // Signed volume with the consistent winding (divergence theorem).
      double volume6 = 0.0;
      for (std::uint32_t t : shell) {
        const auto& [a, b, c] = mesh.triangles[t];
        const double v = mesh.vertices_mm[a].dot(mesh.vertices_mm[b].cross(mesh.vertices_mm[c]));
        volume6 += turn[t] ? -v : v;
      }
      turn_all = volume6 < 0.0;
      const bool inverted_as_given = turned == 0 && turn_all;
      if (inverted_as_given) ++m.inverted_shells;
    } else {
      turn_all = 2 * turned > shell.size();
    }
    for (std::uint32_t t : shell) {
      const bool f = (turn[t] != 0) != turn_all;
      if (f) ++m.flipped_triangles;
      if (flip) (*flip)[t] = f;
    }
  }
  return m;
}

}  // namespace

MeshTopology mesh_topology(const TriangleMesh& mesh) {
  return analyse(mesh, nullptr);
}

MeshTopology orient_mesh(TriangleMesh& mesh) {
  std::vector<std::uint8_t> flip(mesh.triangles.size(), 0);
  const MeshTopology m = analyse(mesh, &flip);
  for (std::size_t t = 0; t < flip.size(); ++t)
    if (flip[t]) std::swap(mesh.triangles[t][1], mesh.triangles[t][2]);
  if (m.flipped_triangles > 0) mesh.normals.clear();
  return m;
}

}  // namespace truecut::offline
