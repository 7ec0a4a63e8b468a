// Options and reports shared by the mesh and point-cloud readers and writers.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace truecut::offline {

enum class MeshFormat {
  kStl,
  kPly,
  kXyz,  // points as text: .xyz, .txt, .csv (comma-separated XYZ)
};

enum class DegenerateFaces {
  kError,  // throw MeshIoError naming the first degenerate face
  kDrop,   // remove them and count them in MeshReadReport
};

struct MeshReadOptions {
  DegenerateFaces degenerate_faces = DegenerateFaces::kError;
  // A triangle is degenerate (zero area) when |(b−a)×(c−a)| ≤ tolerance·L²,
  // L being its longest edge: scale-free, so it catches repeated corners and
  // exactly collinear corners in any unit without flagging small but sound
  // triangles.
  double degenerate_tolerance = 1e-12;
  // STL stores every facet's three corners separately; welding merges corners
  // whose coordinates are bit-identical (after −0 → +0) into one vertex.
  bool weld_stl_vertices = true;
};

// A triangle DegenerateFaces::kDrop removed.
struct DroppedTriangle {
  std::size_t triangle = 0;  // its index among the triangles before dropping
  std::size_t face = 0;      // the STL facet or PLY face it came from
  double area_mm2 = 0.0;
  double longest_edge_mm = 0.0;
};

struct MeshReadReport {
  MeshFormat format = MeshFormat::kStl;
  // "ascii", "binary" (STL), "binary_little_endian" or "binary_big_endian".
  std::string encoding;
  std::size_t faces_in_file = 0;          // STL facets or PLY face records
  std::size_t polygons_triangulated = 0;  // PLY faces with more than 3 corners
  std::size_t degenerate_triangles_dropped = 0;
  std::vector<DroppedTriangle> dropped_triangles;  // each of them, in file order
  std::size_t stl_corners_welded = 0;              // corners merged into an earlier vertex
  // PLY comment and obj_info lines, the STL header or solid names.
  std::vector<std::string> comments;
};

enum class StlEncoding { kBinary, kAscii };
enum class PlyEncoding { kBinaryLittleEndian, kBinaryBigEndian, kAscii };

struct PointTextFormat {
  char separator = ' ';  // ' ' for .xyz/.txt, ',' for .csv
  bool header = false;   // first line "x y z [nx ny nz]" with the separator
};

}  // namespace truecut::offline
