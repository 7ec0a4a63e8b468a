// part.json → stock, surfaces, facet surface ids; nominal STL + part.json →
// dexel model. Errors name the file and the key.
#include "truecut/sim/cutting/part_file.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "truecut/offline/stl_io.hpp"

namespace truecut::sim::cutting {

namespace {

using Json = nlohmann::json;

[[noreturn]] void fail(const std::filesystem::path& file, const std::string& key,
                       const std::string& message) {
  throw PartFileError(file.string() + ": " + key + ": " + message);
}

const Json& member(const std::filesystem::path& file, const Json& obj, const std::string& key,
                   const std::string& path) {
  if (!obj.is_object() || !obj.contains(key)) fail(file, path, "missing");
  return obj.at(key);
}

Eigen::Vector3d vec3(const std::filesystem::path& file, const Json& v, const std::string& key) {
  if (!v.is_array() || v.size() != 3) fail(file, key, "must be an array of 3 numbers");
  Eigen::Vector3d out;
  for (int i = 0; i < 3; ++i) {
    if (!v[i].is_number() || !std::isfinite(v[i].get<double>()))
      fail(file, key + "[" + std::to_string(i) + "]", "must be a finite number");
    out[i] = v[i].get<double>();
  }
  return out;
}

int integer(const std::filesystem::path& file, const Json& v, const std::string& key) {
  if (!v.is_number_integer()) fail(file, key, "must be an integer");
  return v.get<int>();
}

}  // namespace

PartStock read_part_stock(const std::filesystem::path& part_json) {
  std::ifstream in(part_json, std::ios::binary);
  if (!in) throw PartFileError(part_json.string() + ": cannot open");
  std::stringstream text;
  text << in.rdbuf();
  Json j;
  try {
    j = Json::parse(text.str());
  } catch (const Json::parse_error& e) {
    throw PartFileError(part_json.string() + ": not JSON (" + e.what() + ")");
  }
  if (!j.is_object()) throw PartFileError(part_json.string() + ": not a JSON object");
  const Json& version = member(part_json, j, "truecut_part", "truecut_part");
  if (!version.is_number_integer() || version.get<int>() != 1)
    fail(part_json, "truecut_part", "must be 1");
  PartStock out;
  const Json& stock = member(part_json, j, "stock", "stock");
  if (!stock.is_array() || stock.empty())
    fail(part_json, "stock", "must be a non-empty array of boxes");
  for (std::size_t i = 0; i < stock.size(); ++i) {
    const std::string key = "stock[" + std::to_string(i) + "]";
    StockBox b;
    b.min_mm =
        vec3(part_json, member(part_json, stock[i], "min_mm", key + ".min_mm"), key + ".min_mm");
    b.max_mm =
        vec3(part_json, member(part_json, stock[i], "max_mm", key + ".max_mm"), key + ".max_mm");
    if ((b.max_mm.array() <= b.min_mm.array()).any())
      fail(part_json, key, "max_mm must exceed min_mm on every axis");
    out.stock.push_back(b);
  }
  const Json& surfaces = member(part_json, j, "surfaces", "surfaces");
  if (!surfaces.is_array()) fail(part_json, "surfaces", "must be an array");
  for (std::size_t i = 0; i < surfaces.size(); ++i) {
    const std::string key = "surfaces[" + std::to_string(i) + "].id";
    out.surface_ids.push_back(integer(part_json, member(part_json, surfaces[i], "id", key), key));
  }
  const Json& ids = member(part_json, j, "triangle_surface_ids", "triangle_surface_ids");
  if (!ids.is_array()) fail(part_json, "triangle_surface_ids", "must be an array");
  out.triangle_surface_ids.reserve(ids.size());
  for (std::size_t i = 0; i < ids.size(); ++i) {
    const std::string key = "triangle_surface_ids[" + std::to_string(i) + "]";
    const int id = integer(part_json, ids[i], key);
    if (std::find(out.surface_ids.begin(), out.surface_ids.end(), id) == out.surface_ids.end())
      fail(part_json, key, "surface " + std::to_string(id) + " is not in surfaces");
    out.triangle_surface_ids.push_back(id);
  }
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
