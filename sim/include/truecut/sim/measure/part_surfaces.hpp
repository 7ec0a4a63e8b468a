// The surface labels of a nominal model as part.json stores them
// (docs/parts.md): the surfaces with their compensate flags and one id per
// triangle of nominal.stl; read with the one part.json reader
// (truecut/sim/part_file.hpp).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "truecut/sim/part_file.hpp"

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
// file and the key (or the parse position). The part.json reader's error.
using PartFileError = sim::PartFileError;

PartSurfaces read_part_surfaces(const std::filesystem::path& part_json);

}  // namespace truecut::sim::measure
