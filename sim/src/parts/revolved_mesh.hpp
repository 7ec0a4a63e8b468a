// Closed meshes of solids of revolution about +Z: a profile polyline in the
// (ρ, z) half-plane, each profile point swept into a ring of vertices (or a
// single pole vertex where ρ = 0), neighbouring rings stitched into
// triangles. Rings may have different vertex counts; each ring is created
// once, so the mesh is watertight by construction.
#pragma once

#include <vector>

#include "parts/mesh_builder.hpp"

namespace truecut::sim::parts {

struct ProfilePoint {
  double rho_mm = 0;
  double z_mm = 0;
};

// `profile` runs from the bottom pole (ρ = 0) over the solid's outside to
// the top pole (ρ = 0) — the solid lies to the left when walking along it
// in the (ρ, z) plane (ρ to the right, z up). `surface[i]` labels the band between profile points
// i and i + 1. Ring vertex counts: max(8, ⌈2πρ / edge⌉), vertex 0 at +X.
void revolve(MeshBuilder& b, const std::vector<ProfilePoint>& profile,
             const std::vector<int>& surface, double edge_mm);

}  // namespace truecut::sim::parts
