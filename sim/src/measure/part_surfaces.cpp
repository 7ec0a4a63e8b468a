#include "truecut/sim/measure/part_surfaces.hpp"

#include <algorithm>

namespace truecut::sim::measure {

std::vector<std::int32_t> PartSurfaces::compensated_ids() const {
  std::vector<std::int32_t> ids;
  for (const PartSurfaceLabel& s : surfaces)
    if (s.compensate) ids.push_back(s.id);
  std::sort(ids.begin(), ids.end());
  return ids;
}

bool PartSurfaces::has(int id) const {
  return std::any_of(surfaces.begin(), surfaces.end(),
                     [id](const PartSurfaceLabel& s) { return s.id == id; });
}

PartSurfaces read_part_surfaces(const std::filesystem::path& part_json) {
  PartFile p = read_part_file(part_json, kPartSurfaces | kPartTriangleSurfaceIds);
  PartSurfaces out;
  for (const PartSurface& s : p.metadata.surfaces)
    out.surfaces.push_back({s.id, s.name, s.compensate});
  out.triangle_surface_ids.assign(p.triangle_surface_ids.begin(), p.triangle_surface_ids.end());
  return out;
}

}  // namespace truecut::sim::measure
