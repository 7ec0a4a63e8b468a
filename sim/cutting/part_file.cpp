// part.json → stock, surfaces, facet surface ids (through the one part.json
// reader, truecut/sim/part_file.hpp); nominal STL + part.json → dexel model.
// Errors name the file and the key.
#include "truecut/sim/cutting/part_file.hpp"

#include <algorithm>

#include "truecut/offline/stl_io.hpp"
#include "truecut/sim/part_file.hpp"

namespace truecut::sim::cutting {

namespace {

[[noreturn]] void fail(const std::filesystem::path& file, const std::string& key,
                       const std::string& message) {
  throw PartFileError(file.string(), key, message, PartFileError::Wording::kPlain);
}

}  // namespace

PartStock read_part_stock(const std::filesystem::path& part_json) {
  sim::PartFile p;
  try {
    p = read_part_file(part_json,
                       kPartVersion | kPartStock | kPartSurfaces | kPartTriangleSurfaceIds);
  } catch (const PartFileError& e) {
    if (e.key().empty()) throw;
    fail(part_json, e.key(), e.detail());  // this library's "FILE: key: message"
  }
  PartStock out;
  out.stock = std::move(p.metadata.stock);
  for (const PartSurface& s : p.metadata.surfaces)
    out.surface_ids.push_back(s.id);
  out.triangle_surface_ids = std::move(p.triangle_surface_ids);
  return out;
}

DexelModel load_dexel_model(const std::filesystem::path& nominal_stl,
                            const std::filesystem::path& part_json, const DexelOptions& options) {
  const PartStock part = read_part_stock(part_json);
  for (int id : options.surfaces)
    if (std::find(part.surface_ids.begin(), part.surface_ids.end(), id) == part.surface_ids.end())
      fail(part_json, "surfaces", "has no surface " + std::to_string(id) + " (asked for)");
  const offline::TriangleMesh mesh = offline::read_stl(nominal_stl);
  if (mesh.triangles.size() != part.triangle_surface_ids.size())
    fail(part_json, "triangle_surface_ids",
         std::to_string(part.triangle_surface_ids.size()) + " ids, but " + nominal_stl.string() +
             " has " + std::to_string(mesh.triangles.size()) + " facets");
  return DexelModel::build(mesh, part.triangle_surface_ids, part.stock, options);
}

}  // namespace truecut::sim::cutting
