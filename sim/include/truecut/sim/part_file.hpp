// Reading part.json, the inverse of part_json() / write_part()
// (docs/parts.md): one reader for every user of the file (cutting model,
// CMM, tool_geometry component, `truecut field`, `truecut demo`).
//
//   PartFile p = read_part_file("out/implant/part.json");
//   for (const PartTool& t : p.metadata.tools) ...
//   PartFile labels = read_part_file(file, kPartSurfaces | kPartTriangleSurfaceIds);
//
// The second argument names the top-level keys the caller cannot do
// without; a missing one is an error. Every key that is present is checked,
// whatever the caller needs. Its own library (truecut_part_file: nlohmann
// JSON and Eigen only), so that components can link it.
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "truecut/sim/part_metadata.hpp"

namespace truecut::sim {

// what(): "FILE: key 'KEY': DETAIL", or "FILE: DETAIL" when the file cannot
// be read or is not JSON (key empty). The one error type for part.json, also
// of the cutting model's checks (truecut/sim/cutting/part_file.hpp), which
// word it "FILE: KEY: DETAIL" (Wording::kPlain).
class PartFileError : public std::runtime_error {
 public:
  enum class Wording { kQuotedKey, kPlain };
  PartFileError(std::string file, std::string key, std::string detail,
                Wording wording = Wording::kQuotedKey);
  const std::string& file() const { return file_; }
  const std::string& key() const { return key_; }  // e.g. "tools[1].radius_mm"
  const std::string& detail() const { return detail_; }

 private:
  std::string file_, key_, detail_;
};

// part.json's "mesh": a summary of nominal.stl.
struct PartMeshSummary {
  std::string file;  // "nominal.stl"
  std::size_t vertices = 0;
  std::size_t triangles = 0;
  double volume_mm3 = 0;  // signed volume
};

struct PartFile {
  int version = 0;               // "truecut_part"; 0 when the file does not say
  std::string units;             // "mm"
  std::string programmed_point;  // "tool tip"
  std::optional<PartOptions> options;
  // name, frame, material, stock, tools, surfaces, operations and the A
  // travel (rotary_travel_deg.a; defaults of PartMetadata when absent).
  PartMetadata metadata;
  std::optional<PartMeshSummary> mesh;
  std::vector<int> triangle_surface_ids;  // one per STL facet, in order

  const PartTool* tool(int number) const;            // nullptr when not listed
  const PartSurface* surface(int id) const;          // nullptr when not listed
  std::vector<int> compensated_surface_ids() const;  // ascending
};

// Top-level keys a caller needs (bits, combined with |).
enum PartKey : unsigned {
  kPartVersion = 1u << 0,  // "truecut_part" (must be 1 whenever present)
  kPartStock = 1u << 1,
  kPartTools = 1u << 2,
  kPartSurfaces = 1u << 3,
  kPartOperations = 1u << 4,
  kPartTriangleSurfaceIds = 1u << 5,
};
inline constexpr unsigned kPartAllKeys = kPartVersion | kPartStock | kPartTools | kPartSurfaces |
                                         kPartOperations | kPartTriangleSurfaceIds;

// Throws PartFileError naming the file and the key.
PartFile read_part_file(const std::filesystem::path& file, unsigned required = kPartAllKeys);
// The same for text already in memory; `name` stands for the file in errors.
PartFile parse_part_file(std::string_view text, const std::string& name,
                         unsigned required = kPartAllKeys);

}  // namespace truecut::sim
