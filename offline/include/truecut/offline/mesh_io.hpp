// Reading and writing meshes and point clouds in any supported format,
// chosen by content and file extension (see docs/formats.md, "Meshes and
// point clouds").
#pragma once

#include "truecut/offline/mesh.hpp"
#include "truecut/offline/mesh_io_error.hpp"
#include "truecut/offline/mesh_io_options.hpp"
#include "truecut/offline/ply_io.hpp"
#include "truecut/offline/point_text_io.hpp"
#include "truecut/offline/stl_io.hpp"

#include <filesystem>
#include <optional>

namespace truecut::offline {

// From the extension alone: .stl, .ply, .xyz, .txt, .csv (case-insensitive).
std::optional<MeshFormat> format_from_extension(const std::filesystem::path& file);

// Content first (the "ply" magic, a binary STL whose facet count matches the
// file size, an ASCII STL's "solid … facet"), then the extension, then
// numeric text. Throws MeshIoError for an empty file or an unknown format.
MeshFormat detect_format(const std::filesystem::path& file);

// A point format gives a mesh without triangles.
TriangleMesh read_mesh(const std::filesystem::path& file, const MeshReadOptions& options = {},
                       MeshReadReport* report = nullptr);
// Faces in the file are read (and checked) but not returned.
PointCloud read_point_cloud(const std::filesystem::path& file, const MeshReadOptions& options = {},
                            MeshReadReport* report = nullptr);

struct MeshWriteOptions {
  bool ascii = false;      // ASCII STL / ASCII PLY instead of binary
  std::string comment;     // STL header / PLY comment
  bool csv_header = true;  // .csv files get an "x,y,z[,nx,ny,nz]" line
};

// By extension: .stl or .ply (a point format cannot hold triangles and is
// refused unless the mesh has none). Atomic.
void write_mesh(const std::filesystem::path& file, const TriangleMesh& mesh,
                const MeshWriteOptions& options = {});
// By extension: .ply, .xyz, .txt, .csv. Atomic.
void write_point_cloud(const std::filesystem::path& file, const PointCloud& cloud,
                       const MeshWriteOptions& options = {});

}  // namespace truecut::offline
