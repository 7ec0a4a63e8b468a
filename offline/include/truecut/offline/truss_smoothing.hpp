// Truss smoothing of compensation vectors on the nominal mesh, after the 3D
// model adaptation source (Sortino et al., CAD 48 (2014)): every mesh edge is
// a bar of stiffness kb, every vertex with a valid measurement is tied to its
// measured displacement v_i by a spring of stiffness kc. The equilibrium is
//
//   (kb/kc · K + C) d = C v,
//
// C = diag(c_i), c_i = 1 for a valid vertex and 0 for an invalid one. Two
// stiffnesses K (TrussStiffness):
//
// - kAxialBars (the source's truss): a bar resists only a change of its
//   length. Bar a–b with unit direction e adds kb·e eᵀ to the blocks aa and
//   bb and −kb·e eᵀ to ab and ba of a 3n × 3n matrix: x, y and z are
//   coupled. A displacement across every bar of a vertex (e.g. along the
//   normal of a flat face) strains nothing, so it is not smoothed.
// - kZeroLengthSprings (this project's default): K the graph Laplacian of the
//   edges, x, y, z solved independently; every component of the difference
//   between neighbours is resisted, the normal one on a flat face included.
//   A constant field has no strain and passes unchanged in both.
//
// With all vertices valid this is d = (kb/kc · K + I)⁻¹ v; invalid vertices
// are interpolated by the truss alone. A connected component without a single
// valid vertex has nothing to hold it: its vertices get d = 0 and are
// reported unsupported. With axial bars an invalid vertex may also move in a
// direction no bar resists (a mechanism): there it gets 0 (a spring of
// 1e-9 · kb/kc to zero picks that solution).
//
// Sign: the source writes P' = P − d with v the measured error; here v are
// compensation vectors (already mirrored), so the adapted vertex is P + d.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "truecut/offline/mesh.hpp"

namespace truecut::offline {

enum class TrussEdgeWeight {
  kUniform,        // every bar kb (the source)
  kInverseLength,  // bar i–j: kb · (mean edge length / |Pi − Pj|)
};

enum class TrussStiffness {
  kZeroLengthSprings,  // graph Laplacian per component (this project's default)
  kAxialBars,          // bars resisting only their change of length (the source)
};

struct TrussOptions {
  // kb/kc. Larger smooths more (white noise on a regular triangulation is
  // reduced to about 1/2 at 0.2, the source's value, 1/3.5 at 1); the
  // smoothing length is in edges, not mm. 1 by a closed-loop sweep on the
  // implant (docs/offline.md, "Noise"): at 50 µm scanner noise the shaft
  // faces' spread fell from 5.3–9.3 to 3.4–6.8 µm against 0.2, at 20 µm it
  // did not change; 5 gave the same as 1.
  double kb_over_kc = 1.0;
  TrussEdgeWeight edge_weight = TrussEdgeWeight::kUniform;
  TrussStiffness stiffness = TrussStiffness::kZeroLengthSprings;
};

struct TrussResult {
  std::vector<Eigen::Vector3d> displacement_mm;  // d, one per vertex
  // 0 where the vertex's component had no valid vertex (d = 0 there).
  std::vector<std::uint8_t> supported;
  std::int64_t unsupported_count = 0;
  std::int64_t edge_count = 0;
};

// The truss's bars: unique undirected edges (i < j) of the triangles, sorted.
std::vector<std::array<std::uint32_t, 2>> truss_bars(std::span<const Triangle> triangles);

// vectors_mm and valid have one entry per vertex (valid: nonzero = valid;
// invalid entries of vectors_mm are ignored and may be NaN). vertices_mm is
// needed only for TrussEdgeWeight::kInverseLength and TrussStiffness::kAxialBars
// (may be empty otherwise).
// Throws std::invalid_argument on size mismatch, out-of-range vertex index,
// negative or non-finite kb_over_kc, or a non-finite valid vector.
TrussResult smooth_truss(std::span<const Eigen::Vector3d> vertices_mm,
                         std::span<const Triangle> triangles,
                         std::span<const Eigen::Vector3d> vectors_mm,
                         std::span<const std::uint8_t> valid, const TrussOptions& options = {});

}  // namespace truecut::offline
