// PLY (Stanford polygon file) meshes and point clouds: ascii,
// binary_little_endian and binary_big_endian.
//
// Read: the "vertex" element's x, y, z (any numeric type) and, when all three
// are present, nx, ny, nz; the "face" element's "vertex_indices" (or
// "vertex_index") list with any integer count and index types. Polygons are
// fan-triangulated. All other properties and elements, lists included, are
// skipped. Write: float64 coordinates and normals, faces as
// "list uchar uint vertex_indices".
#pragma once

#include "truecut/offline/mesh.hpp"
#include "truecut/offline/mesh_io_options.hpp"

#include <filesystem>
#include <string_view>

namespace truecut::offline {

// Throws MeshIoError. A file without a face element gives a mesh without
// triangles.
TriangleMesh read_ply(const std::filesystem::path& file, const MeshReadOptions& options = {},
                      MeshReadReport* report = nullptr);

// Atomic (FILE.tmp, then rename). `comment` becomes a header comment line.
void write_ply(const std::filesystem::path& file, const TriangleMesh& mesh,
               PlyEncoding encoding = PlyEncoding::kBinaryLittleEndian,
               std::string_view comment = {});
void write_ply(const std::filesystem::path& file, const PointCloud& cloud,
               PlyEncoding encoding = PlyEncoding::kBinaryLittleEndian,
               std::string_view comment = {});

}  // namespace truecut::offline
