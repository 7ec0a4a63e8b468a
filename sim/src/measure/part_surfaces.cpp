#include "truecut/sim/measure/part_surfaces.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <fstream>
#include <limits>

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
  const std::string name = part_json.string();
  std::ifstream in(part_json, std::ios::binary);
  if (!in) throw PartFileError(name + ": cannot open");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw PartFileError(name + ": not valid JSON (byte " + std::to_string(e.byte) + ")");
  }
  auto fail = [&](const std::string& key, const std::string& what) -> PartFileError {
    return PartFileError(name + ": key '" + key + "': " + what);
  };
  PartSurfaces out;
  if (!j.is_object() || !j.contains("surfaces") || !j["surfaces"].is_array())
    throw fail("surfaces", "missing or not an array");
  for (std::size_t i = 0; i < j["surfaces"].size(); ++i) {
    const nlohmann::json& s = j["surfaces"][i];
    const std::string key = "surfaces[" + std::to_string(i) + "]";
    if (!s.is_object() || !s.contains("id") || !s["id"].is_number_integer())
      throw fail(key + ".id", "missing or not an integer");
    PartSurfaceLabel label;
    label.id = s["id"].get<int>();
    if (s.contains("name") && s["name"].is_string()) label.name = s["name"].get<std::string>();
    if (s.contains("compensate")) {
      if (!s["compensate"].is_boolean()) throw fail(key + ".compensate", "not true or false");
      label.compensate = s["compensate"].get<bool>();
    }
    out.surfaces.push_back(label);
  }
  if (!j.contains("triangle_surface_ids") || !j["triangle_surface_ids"].is_array())
    throw fail("triangle_surface_ids", "missing or not an array");
  const nlohmann::json& ids = j["triangle_surface_ids"];
  out.triangle_surface_ids.reserve(ids.size());
  for (std::size_t i = 0; i < ids.size(); ++i) {
    if (!ids[i].is_number_integer())
      throw fail("triangle_surface_ids[" + std::to_string(i) + "]", "not an integer");
    const auto v = ids[i].get<long long>();
    if (v < std::numeric_limits<std::int32_t>::min() ||
        v > std::numeric_limits<std::int32_t>::max())
      throw fail("triangle_surface_ids[" + std::to_string(i) + "]", "out of range");
    out.triangle_surface_ids.push_back(static_cast<std::int32_t>(v));
  }
  return out;
}

}  // namespace truecut::sim::measure
