// Points as text, one per line: "x y z" or "x y z nx ny nz" (.xyz, .txt) or
// the same separated by commas (.csv).
//
// Read: blanks, ',' or ';' separate values; '#' starts a comment; blank lines
// are ignored. An optional first line of column names is recognised by not
// being numeric; when it names x, y, z (and nx, ny, nz or normal_x, normal_y,
// normal_z), columns are taken by name and may come in any order among
// others, otherwise every line must hold 3 or 6 values.
#pragma once

#include "truecut/offline/mesh.hpp"
#include "truecut/offline/mesh_io_options.hpp"

#include <filesystem>

namespace truecut::offline {

// Throws MeshIoError (naming the line) on a malformed line, a non-finite
// value or a file with neither points nor a header.
PointCloud read_point_text(const std::filesystem::path& file, MeshReadReport* report = nullptr);

// Atomic (FILE.tmp, then rename). Values are written with the shortest text
// that reads back to the identical double.
void write_point_text(const std::filesystem::path& file, const PointCloud& cloud,
                      const PointTextFormat& format = {});

}  // namespace truecut::offline
