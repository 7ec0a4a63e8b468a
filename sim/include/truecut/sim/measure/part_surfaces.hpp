// The surface labels of a nominal model as part.json stores them
// (docs/parts.md): the surfaces with their compensate flags and one id per
// triangle of nominal.stl.
#pragma once

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace truecut::sim::measure {

struct PartSurfaceLabel {
  int id = 0;
  std::string name;
  bool compensate = false;
};

struct PartSurfaces {
  std::vector<PartSurfaceLabel> surfaces;
  std::vector<std::int32_t> triangle_surface_ids;  // one per STL facet, in order

  // The ids with compensate = true, ascending.
  std::vector<std::int32_t> compensated_ids() const;
  bool has(int id) const;
};

// Thrown for unreadable JSON or a missing or wrong key; what() names the
// file and the key (or the parse position).
class PartFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

PartSurfaces read_part_surfaces(const std::filesystem::path& part_json);

}  // namespace truecut::sim::measure
