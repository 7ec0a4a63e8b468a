// The PLY header: format line, elements with their properties, comments.
#pragma once

#include "mesh_io/buffered_reader.hpp"
#include "mesh_io/byte_order.hpp"
#include "truecut/offline/mesh_io_options.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace truecut::offline::mesh_io {

enum class PlyType : std::uint8_t {
  kInt8,
  kUint8,
  kInt16,
  kUint16,
  kInt32,
  kUint32,
  kFloat32,
  kFloat64
};

std::size_t ply_type_size(PlyType type);
bool ply_type_is_integer(PlyType type);

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::kFloat32;  // the item type for lists
  bool is_list = false;
  PlyType count_type = PlyType::kUint8;
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;

  bool has_lists() const;
  // Bytes per binary record; for elements with lists, the least possible
  // (every list empty).
  std::size_t min_record_bytes() const;
  // Index of the named property, or -1.
  int find(std::string_view name) const;
};

struct PlyHeader {
  PlyEncoding encoding = PlyEncoding::kAscii;
  std::vector<PlyElement> elements;
  std::vector<std::string> comments;  // comment and obj_info lines
  std::size_t lines = 0;              // header lines, "ply" to "end_header"
};

// Reads up to and including "end_header"; throws MeshIoError naming the
// header line on anything malformed.
PlyHeader read_ply_header(BufferedReader& in);

// Any PLY scalar at p, converted.
double load_ply_double(const char* p, PlyType type, ByteOrder order);
std::int64_t load_ply_integer(const char* p, PlyType type, ByteOrder order);

}  // namespace truecut::offline::mesh_io
