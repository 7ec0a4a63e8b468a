// Compensation points: where on the nominal surface an error vector is
// measured and a compensation vector is applied. Either the nominal mesh's
// vertices or an even sampling of the surfaces named for compensation.
#pragma once

#include "truecut/offline/mesh.hpp"

#include <cstdint>
#include <span>
#include <vector>

namespace truecut::offline {

struct CompensationPoints {
  std::vector<Eigen::Vector3d> positions_mm;  // on the nominal surface, workpiece frame
  std::vector<Eigen::Vector3d> normals;       // unit nominal normals (the mesh's winding)
  std::vector<std::int32_t> surface_ids;
  std::vector<std::uint32_t> triangles;  // a nominal triangle that holds the point

  std::size_t size() const { return positions_mm.size(); }
};

// Every vertex used by a triangle of one of `surfaces` (empty: all
// surfaces), in vertex order. Normal: the angle-weighted vertex normal over
// all incident triangles; surface id and triangle: those of the lowest-index
// incident triangle on a selected surface (a vertex on an edge between two
// surfaces belongs to both; it is listed once).
CompensationPoints compensation_points_at_vertices(
    const TriangleMesh& nominal, std::span<const std::int32_t> triangle_surface_ids,
    std::span<const std::int32_t> surfaces = {});

// An even sampling of the triangles of `surfaces` (empty: all), about one
// point per spacing_mm: candidates on a lattice of spacing/4 in every
// triangle are thinned to the one nearest the centre of each cube of edge
// spacing_mm (cubes aligned to the mesh's bounding box, separately per
// surface). Normal: the triangle's face normal. Deterministic; ordered by
// triangle.
CompensationPoints sample_compensation_points(const TriangleMesh& nominal,
                                              std::span<const std::int32_t> triangle_surface_ids,
                                              double spacing_mm,
                                              std::span<const std::int32_t> surfaces = {});

}  // namespace truecut::offline
