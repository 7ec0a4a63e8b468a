// The mirror method and the compensation matrix (optical-compensation
// source): the compensation vector at a point is the error vector mirrored at
// the nominal point, and the matrix lists x y z dx dy dz per point.
#pragma once

#include "truecut/offline/compensation_points.hpp"
#include "truecut/offline/error_vectors.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace truecut::offline {

struct CompensationMatrix {
  std::vector<Eigen::Vector3d> positions_mm;  // nominal points, workpiece frame
  std::vector<Eigen::Vector3d> vectors_mm;    // compensation = −error; zero where invalid
  std::vector<std::uint8_t> valid;
  std::vector<std::int32_t> surface_ids;
  // Optional: the mirror of the raw error vectors, written as
  // raw_dx,raw_dy,raw_dz when vectors_mm holds a smoothed compensation.
  std::vector<Eigen::Vector3d> raw_vectors_mm;

  std::size_t size() const { return positions_mm.size(); }
};

// Mirror method: compensation = −error, point by point; invalid errors give
// a zero vector marked invalid. Throws std::invalid_argument when the sizes
// differ.
CompensationMatrix mirror(const CompensationPoints& points, const ErrorVectors& errors);

// CSV (docs/formats.md, "Compensation matrix"): '#' comment lines naming
// format version, frame and units (plus `comment`, one '#' line per line of
// it), the header `x,y,z,dx,dy,dz,valid,surface_id` (plus
// `,raw_dx,raw_dy,raw_dz` when raw_vectors_mm is set), one row per point with
// the shortest decimal that reads back to the identical double. Atomic
// (FILE.tmp, then rename); throws MeshIoError on I/O failure or a
// non-finite value.
void write_compensation_matrix(const std::filesystem::path& file, const CompensationMatrix& matrix,
                               const std::string& comment = {});

}  // namespace truecut::offline
