// The topology of a triangle mesh as CAD exports it: open boundaries,
// non-manifold edges, faces wound against their neighbours, shells turned
// inside out; and the repair of the winding where it is well defined
// (docs/offline.md, "Meshes as they come from CAD").
#pragma once

#include <cstddef>

#include "truecut/offline/mesh.hpp"

namespace truecut::offline {

struct MeshTopology {
  std::size_t edges = 0;               // distinct edges (by vertex index)
  std::size_t boundary_edges = 0;      // used by one triangle: the shell is open there
  std::size_t nonmanifold_edges = 0;   // used by more than two triangles
  std::size_t inconsistent_edges = 0;  // two triangles traverse it the same way
  std::size_t shells = 0;              // connected through two-triangle edges
  std::size_t open_shells = 0;         // with a boundary or non-manifold edge
  std::size_t nonorientable_shells = 0;
  // Closed shells whose consistent winding encloses a negative volume
  // (every normal points inwards).
  std::size_t inverted_shells = 0;
  // Triangles orient_mesh turns (or would turn) round.
  std::size_t flipped_triangles = 0;

  bool clean() const {
    return boundary_edges == 0 && nonmanifold_edges == 0 && inconsistent_edges == 0 &&
           inverted_shells == 0;
  }
};

// Counts only; the mesh is not changed.
MeshTopology mesh_topology(const TriangleMesh& mesh);

// Makes every orientable shell's winding consistent, from its neighbours
// across two-triangle edges: a closed shell so that it encloses a positive
// volume (normals outwards), an open shell towards the winding most of its
// triangles already have. Non-orientable shells are left alone. Returns the
// topology found before the repair (flipped_triangles: how many it turned).
MeshTopology orient_mesh(TriangleMesh& mesh);

}  // namespace truecut::offline
