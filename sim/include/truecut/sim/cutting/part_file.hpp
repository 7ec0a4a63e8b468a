// What the cutting model needs from a benchmark part's part.json (see
// docs/parts.md): the stock boxes, the surface ids and the surface id of each
// nominal STL facet.
#pragma once

#include <filesystem>
#include <vector>

#include "truecut/sim/benchmark_parts.hpp"
#include "truecut/sim/cutting/dexel_model.hpp"
#include "truecut/sim/part_file.hpp"

namespace truecut::sim::cutting {

// part.json's one error type; here worded "FILE: key: message"
// (PartFileError::Wording::kPlain).
using sim::PartFileError;

struct PartStock {
  std::vector<StockBox> stock;
  std::vector<int> surface_ids;
  std::vector<int> triangle_surface_ids;
};

PartStock read_part_stock(const std::filesystem::path& part_json);

// Reads the nominal STL and part.json and builds the dexel model. Throws
// PartFileError naming the file and key (a facet count that does not match
// triangle_surface_ids, an unknown surface id in options.surfaces, ...), and
// offline::MeshIoError for an unreadable STL.
DexelModel load_dexel_model(const std::filesystem::path& nominal_stl,
                            const std::filesystem::path& part_json, const DexelOptions& options);

}  // namespace truecut::sim::cutting
