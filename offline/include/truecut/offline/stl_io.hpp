// STL (stereolithography) triangle meshes, ASCII and binary.
//
// Binary STL stores float32 coordinates: values written are rounded to the
// nearest float. Facet normals in the file are not kept (they are recomputed
// from the corners on writing); the mesh read has no per-vertex normals.
#pragma once

#include "truecut/offline/mesh.hpp"
#include "truecut/offline/mesh_io_options.hpp"

#include <filesystem>
#include <string_view>

namespace truecut::offline {

// Detects ASCII or binary from the content (a binary file whose 80-byte header
// starts with "solid" is still read as binary: the facet count in bytes 80–83
// must match the file size). Throws MeshIoError.
TriangleMesh read_stl(const std::filesystem::path& file, const MeshReadOptions& options = {},
                      MeshReadReport* report = nullptr);

// Atomic (FILE.tmp, then rename). `header` goes into the binary header (at
// most 80 bytes; must not start with "solid") or after "solid " in ASCII.
void write_stl(const std::filesystem::path& file, const TriangleMesh& mesh,
               StlEncoding encoding = StlEncoding::kBinary, std::string_view header = {});

}  // namespace truecut::offline
