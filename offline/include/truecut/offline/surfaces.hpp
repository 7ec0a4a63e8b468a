// Surface ids: one label per triangle naming the surface it belongs to. A
// nominal model may bring its own labels (a PLY face property, a CAD export);
// for an STL without labels they are derived by region growing.
#pragma once

#include "truecut/offline/mesh.hpp"

#include <cstdint>
#include <span>
#include <vector>

namespace truecut::offline {

// Region growing on the dihedral angle: two triangles sharing a manifold edge
// belong to the same surface when the angle between their normals is at most
// max_dihedral_deg. Growth crosses any number of such edges, so a cylinder
// tessellated with 10° steps is one surface under a 30° threshold, while the
// square edges of a box separate its six faces. Boundary and non-manifold
// edges always separate. Ids are 0, 1, … in order of each surface's lowest
// triangle index, so they depend only on the mesh.
std::vector<std::int32_t> segment_surfaces(const TriangleMesh& mesh,
                                           double max_dihedral_deg = 30.0);

// The triangles whose label is one of `surfaces`, ascending (a datum region
// for registration, for example).
std::vector<std::uint32_t> triangles_of_surfaces(std::span<const std::int32_t> triangle_surface_ids,
                                                 std::span<const std::int32_t> surfaces);

}  // namespace truecut::offline
