// Topology counts and winding repair on small meshes whose defects are
// planted by hand: a tetrahedron and a unit cube, closed, opened, with a
// face turned round, turned inside out, and with a third face on an edge.
#include "truecut/offline/mesh_topology.hpp"

#include <gtest/gtest.h>

#include <utility>

#include <Eigen/Geometry>

namespace truecut::offline {
namespace {

// Outward winding: (b − a) × (c − a) points away from the opposite vertex.
TriangleMesh tetrahedron() {
  TriangleMesh m;
  m.vertices_mm = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return m;
}

// The unit cube, 12 triangles, outward winding, welded corners.
TriangleMesh cube() {
  TriangleMesh m;
  for (int i = 0; i < 8; ++i)
    m.vertices_mm.emplace_back(i & 1, (i >> 1) & 1, (i >> 2) & 1);
  m.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                 {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  return m;
}

double signed_volume(const TriangleMesh& m) {
  double v6 = 0;
  for (const auto& [a, b, c] : m.triangles)
    v6 += m.vertices_mm[a].dot(m.vertices_mm[b].cross(m.vertices_mm[c]));
  return v6 / 6;
}

TEST(MeshTopology, ClosedSolidsAreClean) {
  for (const TriangleMesh& m : {tetrahedron(), cube()}) {
    const MeshTopology t = mesh_topology(m);
    EXPECT_TRUE(t.clean());
    EXPECT_EQ(t.shells, 1u);
    EXPECT_EQ(t.open_shells, 0u);
    EXPECT_EQ(t.flipped_triangles, 0u);
    EXPECT_EQ(t.edges, m.triangles.size() * 3 / 2);
    EXPECT_GT(signed_volume(m), 0);
  }
}

TEST(MeshTopology, OneFaceTurnedRoundIsFoundAndTurnedBack) {
  for (std::size_t face : {0u, 5u, 11u}) {
    TriangleMesh m = cube();
    std::swap(m.triangles[face][1], m.triangles[face][2]);
    const MeshTopology t = orient_mesh(m);
    EXPECT_EQ(t.inconsistent_edges, 3u) << face;
    EXPECT_EQ(t.flipped_triangles, 1u) << face;
    EXPECT_EQ(t.inverted_shells, 0u) << face;
    EXPECT_EQ(m.triangles, cube().triangles) << face;
    EXPECT_TRUE(mesh_topology(m).clean()) << face;
  }
}

TEST(MeshTopology, ASolidInsideOutIsTurnedOutwards) {
  TriangleMesh m = cube();
  for (auto& t : m.triangles)
    std::swap(t[1], t[2]);
  EXPECT_LT(signed_volume(m), 0);
  const MeshTopology t = orient_mesh(m);
  EXPECT_EQ(t.inconsistent_edges, 0u);
  EXPECT_EQ(t.inverted_shells, 1u);
  EXPECT_EQ(t.flipped_triangles, 12u);
  EXPECT_NEAR(signed_volume(m), 1.0, 1e-12);
  EXPECT_TRUE(mesh_topology(m).clean());
}

TEST(MeshTopology, OpenShellsAndNonManifoldEdgesAreCounted) {
  TriangleMesh open = cube();
  open.triangles.pop_back();  // one triangle of the +x face missing
  MeshTopology t = mesh_topology(open);
  EXPECT_EQ(t.boundary_edges, 3u);
  EXPECT_EQ(t.open_shells, 1u);
  EXPECT_EQ(t.inverted_shells, 0u);
  // An open shell is wound the way most of its triangles are.
  std::swap(open.triangles[2][1], open.triangles[2][2]);
  t = orient_mesh(open);
  EXPECT_EQ(t.flipped_triangles, 1u);
  TriangleMesh expected = cube();
  expected.triangles.pop_back();
  EXPECT_EQ(open.triangles, expected.triangles);

  TriangleMesh fin = tetrahedron();
  fin.vertices_mm.emplace_back(1, 1, -1);
  fin.triangles.push_back({0, 4, 1});  // a third face on edge 0–1
  t = mesh_topology(fin);
  EXPECT_EQ(t.nonmanifold_edges, 1u);
  EXPECT_EQ(t.boundary_edges, 2u);
  EXPECT_EQ(t.shells, 2u);  // the fin hangs on a non-manifold edge only
  EXPECT_FALSE(t.clean());
}

TEST(MeshTopology, TwoSeparateShellsAreEachOriented) {
  TriangleMesh m = tetrahedron();
  const TriangleMesh c = cube();
  const auto offset = static_cast<std::uint32_t>(m.vertices_mm.size());
  for (const auto& v : c.vertices_mm)
    m.vertices_mm.push_back(v + Eigen::Vector3d(5, 0, 0));
  for (auto t : c.triangles) {
    for (auto& v : t)
      v += offset;
    std::swap(t[1], t[2]);  // the cube inside out
    m.triangles.push_back(t);
  }
  const MeshTopology t = orient_mesh(m);
  EXPECT_EQ(t.shells, 2u);
  EXPECT_EQ(t.inverted_shells, 1u);
  EXPECT_EQ(t.flipped_triangles, 12u);
  EXPECT_NEAR(signed_volume(m), 1.0 + 1.0 / 6, 1e-12);
}

}  // namespace
}  // namespace truecut::offline
