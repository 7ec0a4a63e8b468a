// part.json → PartFile. Every error names the file and the key.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <limits>
#include <nlohmann/json.hpp>

#include "truecut/rt/input_file.hpp"
#include "truecut/sim/part_file.hpp"
#include "truecut/sim/part_plausibility.hpp"

namespace truecut::sim {
namespace {

using Json = nlohmann::json;

std::string what_text(const std::string& file, const std::string& key, const std::string& detail,
                      PartFileError::Wording wording) {
  if (key.empty()) return file + ": " + detail;
  if (wording == PartFileError::Wording::kPlain) return file + ": " + key + ": " + detail;
  return file + ": key '" + key + "': " + detail;
}

class Reader {
 public:
  explicit Reader(std::string name) : name_(std::move(name)) {}

  [[noreturn]] void fail(const std::string& key, const std::string& detail) const {
    throw PartFileError(name_, key, detail);
  }

  // obj[key] when present (nullptr otherwise); `required` makes absence an error.
  const Json* find(const Json& obj, const char* key, const std::string& path, bool required) const {
    const auto it = obj.find(key);
    if (it != obj.end()) return &*it;
    if (required) fail(path, "missing");
    return nullptr;
  }

  const Json& object(const Json& v, const std::string& key) const {
    if (!v.is_object()) fail(key, "must be an object");
    return v;
  }

  const Json& array(const Json& v, const std::string& key) const {
    if (!v.is_array()) fail(key, "must be an array");
    return v;
  }

  std::string string(const Json& v, const std::string& key) const {
    if (!v.is_string()) fail(key, "must be a string");
    return v.get<std::string>();
  }

  bool boolean(const Json& v, const std::string& key) const {
    if (!v.is_boolean()) fail(key, "must be true or false");
    return v.get<bool>();
  }

  int integer(const Json& v, const std::string& key) const {
    if (!v.is_number_integer()) fail(key, "must be an integer");
    constexpr long long kMin = std::numeric_limits<std::int32_t>::min();
    constexpr long long kMax = std::numeric_limits<std::int32_t>::max();
    const bool inside = v.is_number_unsigned()
                            ? v.get<unsigned long long>() <= static_cast<unsigned long long>(kMax)
                            : v.get<long long>() >= kMin && v.get<long long>() <= kMax;
    if (!inside) fail(key, "out of range");
    return static_cast<int>(v.get<long long>());
  }

  std::size_t count(const Json& v, const std::string& key) const {
    if (!v.is_number_integer() || (!v.is_number_unsigned() && v.get<long long>() < 0))
      fail(key, "must be an integer >= 0");
    return static_cast<std::size_t>(v.get<unsigned long long>());
  }

  double number(const Json& v, const std::string& key) const {
    if (!v.is_number() || !std::isfinite(v.get<double>())) fail(key, "must be a finite number");
    return v.get<double>();
  }

  double length(const Json& v, const std::string& key) const {
    const double x = number(v, key);
    if (x < 0) fail(key, "must be >= 0");
    return x;
  }

  Eigen::Vector3d vec3(const Json& v, const std::string& key) const {
    if (!v.is_array() || v.size() != 3) fail(key, "must be an array of 3 numbers");
    Eigen::Vector3d out;
    for (int i = 0; i < 3; ++i)
      out[i] = number(v[i], key + "[" + std::to_string(i) + "]");
    return out;
  }

 private:
  std::string name_;
};

std::string at(const std::string& key, std::size_t i) {
  return key + "[" + std::to_string(i) + "]";
}

PartOptions read_options(const Reader& r, const Json& j) {
  r.object(j, "options");
  PartOptions o;
  const std::pair<const char*, double*> fields[] = {{"mesh_edge_mm", &o.mesh_edge_mm},
                                                    {"stepover_mm", &o.stepover_mm},
                                                    {"point_spacing_mm", &o.point_spacing_mm},
                                                    {"step_down_mm", &o.step_down_mm}};
  for (const auto& [key, value] : fields) {
    const std::string path = std::string("options.") + key;
    if (const Json* v = r.find(j, key, path, false)) *value = r.number(*v, path);
  }
  return o;
}

std::vector<StockBox> read_stock(const Reader& r, const Json& j) {
  if (!j.is_array() || j.empty()) r.fail("stock", "must be a non-empty array of boxes");
  std::vector<StockBox> out;
  for (std::size_t i = 0; i < j.size(); ++i) {
    const std::string key = at("stock", i);
    r.object(j[i], key);
    StockBox b;
    b.min_mm = r.vec3(*r.find(j[i], "min_mm", key + ".min_mm", true), key + ".min_mm");
    b.max_mm = r.vec3(*r.find(j[i], "max_mm", key + ".max_mm", true), key + ".max_mm");
    if ((b.max_mm.array() <= b.min_mm.array()).any())
      r.fail(key, "max_mm must exceed min_mm on every axis");
    out.push_back(b);
  }
  return out;
}

std::vector<PartTool> read_tools(const Reader& r, const Json& j) {
  r.array(j, "tools");
  std::vector<PartTool> out;
  for (std::size_t i = 0; i < j.size(); ++i) {
    const std::string key = at("tools", i);
    const Json& t = r.object(j[i], key);
    PartTool tool;
    tool.number = r.integer(*r.find(t, "number", key + ".number", true), key + ".number");
    for (const PartTool& other : out)
      if (other.number == tool.number)
        r.fail(key + ".number", "tool " + std::to_string(tool.number) + " listed twice");
    tool.radius_mm =
        r.length(*r.find(t, "radius_mm", key + ".radius_mm", true), key + ".radius_mm");
    const std::pair<const char*, double*> lengths[] = {{"corner_radius_mm", &tool.corner_radius_mm},
                                                       {"length_mm", &tool.length_mm},
                                                       {"flute_length_mm", &tool.flute_length_mm}};
    for (const auto& [name, value] : lengths) {
      const std::string path = key + "." + name;
      if (const Json* v = r.find(t, name, path, false)) *value = r.length(*v, path);
    }
    if (tool.corner_radius_mm > tool.radius_mm)
      r.fail(key + ".corner_radius_mm", "larger than radius_mm");
    if (const Json* v = r.find(t, "flutes", key + ".flutes", false))
      tool.flutes = static_cast<int>(r.count(*v, key + ".flutes"));
    if (const Json* v = r.find(t, "kind", key + ".kind", false))
      tool.kind = r.string(*v, key + ".kind");
    if (const Json* v = r.find(t, "comment", key + ".comment", false))
      tool.comment = r.string(*v, key + ".comment");
    out.push_back(tool);
  }
  return out;
}

std::vector<PartSurface> read_surfaces(const Reader& r, const Json& j) {
  r.array(j, "surfaces");
  std::vector<PartSurface> out;
  for (std::size_t i = 0; i < j.size(); ++i) {
    const std::string key = at("surfaces", i);
    const Json& s = r.object(j[i], key);
    PartSurface surface;
    surface.id = r.integer(*r.find(s, "id", key + ".id", true), key + ".id");
    if (const Json* v = r.find(s, "name", key + ".name", false))
      surface.name = r.string(*v, key + ".name");
    if (const Json* v = r.find(s, "kind", key + ".kind", false))
      surface.kind = r.string(*v, key + ".kind");
    if (const Json* v = r.find(s, "compensate", key + ".compensate", false))
      surface.compensate = r.boolean(*v, key + ".compensate");
    out.push_back(surface);
  }
  return out;
}

std::vector<int> read_ids(const Reader& r, const Json& j, const std::string& key) {
  r.array(j, key);
  std::vector<int> out;
  out.reserve(j.size());
  for (std::size_t i = 0; i < j.size(); ++i)
    out.push_back(r.integer(j[i], at(key, i)));
  return out;
}

std::vector<PartOperation> read_operations(const Reader& r, const Json& j) {
  r.array(j, "operations");
  std::vector<PartOperation> out;
  for (std::size_t i = 0; i < j.size(); ++i) {
    const std::string key = at("operations", i);
    const Json& o = r.object(j[i], key);
    PartOperation op;
    op.name = r.string(*r.find(o, "name", key + ".name", true), key + ".name");
    op.tool = r.integer(*r.find(o, "tool", key + ".tool", true), key + ".tool");
    if (const Json* v = r.find(o, "strategy", key + ".strategy", false))
      op.strategy = r.string(*v, key + ".strategy");
    if (const Json* v = r.find(o, "surface_ids", key + ".surface_ids", false))
      op.surface_ids = read_ids(r, *v, key + ".surface_ids");
    out.push_back(op);
  }
  return out;
}

void read_rotary_travel(const Reader& r, const Json& j, PartMetadata& m) {
  r.object(j, "rotary_travel_deg");
  const Json* a = r.find(j, "a", "rotary_travel_deg.a", false);
  if (!a) return;
  if (!a->is_array() || a->size() != 2)
    r.fail("rotary_travel_deg.a", "must be an array [min, max]");
  m.a_min_deg = r.number((*a)[0], "rotary_travel_deg.a[0]");
  m.a_max_deg = r.number((*a)[1], "rotary_travel_deg.a[1]");
  if (!(m.a_min_deg <= m.a_max_deg)) r.fail("rotary_travel_deg.a", "min must not exceed max");
}

PartMeshSummary read_mesh(const Reader& r, const Json& j) {
  r.object(j, "mesh");
  PartMeshSummary m;
  if (const Json* v = r.find(j, "file", "mesh.file", false)) m.file = r.string(*v, "mesh.file");
  if (const Json* v = r.find(j, "vertices", "mesh.vertices", false))
    m.vertices = r.count(*v, "mesh.vertices");
  if (const Json* v = r.find(j, "triangles", "mesh.triangles", false))
    m.triangles = r.count(*v, "mesh.triangles");
  if (const Json* v = r.find(j, "volume_mm3", "mesh.volume_mm3", false))
    m.volume_mm3 = r.number(*v, "mesh.volume_mm3");
  return m;
}

}  // namespace

PartFileError::PartFileError(std::string file, std::string key, std::string detail, Wording wording)
    : std::runtime_error(what_text(file, key, detail, wording)),
      file_(std::move(file)),
      key_(std::move(key)),
      detail_(std::move(detail)) {}

const PartTool* PartFile::tool(int number) const {
  for (const PartTool& t : metadata.tools)
    if (t.number == number) return &t;
  return nullptr;
}

const PartSurface* PartFile::surface(int id) const {
  for (const PartSurface& s : metadata.surfaces)
    if (s.id == id) return &s;
  return nullptr;
}

std::vector<int> PartFile::compensated_surface_ids() const {
  std::vector<int> ids;
  for (const PartSurface& s : metadata.surfaces)
    if (s.compensate) ids.push_back(s.id);
  std::sort(ids.begin(), ids.end());
  return ids;
}

PartFile parse_part_file(std::string_view text, const std::string& name, unsigned required) {
  const Reader r(name);
  Json j;
  try {
    j = Json::parse(text);
  } catch (const Json::parse_error& e) {
    r.fail("", "not valid JSON (byte " + std::to_string(e.byte) + ")");
  } catch (const Json::exception& e) {  // a number beyond a double (found by fuzz_part_json)
    std::string what = e.what();
    if (const auto pos = what.find("] "); pos != std::string::npos) what = what.substr(pos + 2);
    r.fail("", "not valid JSON: " + what);
  }
  if (!j.is_object()) r.fail("", "not a JSON object");
  const auto need = [&](unsigned key) { return (required & key) != 0; };

  PartFile p;
  if (const Json* v = r.find(j, "truecut_part", "truecut_part", need(kPartVersion))) {
    if (!v->is_number_integer() || v->get<long long>() != 1) r.fail("truecut_part", "must be 1");
    p.version = 1;
  }
  const std::pair<const char*, std::string*> strings[] = {
      {"name", &p.metadata.name},
      {"units", &p.units},
      {"frame", &p.metadata.frame},
      {"material", &p.metadata.material},
      {"programmed_point", &p.programmed_point}};
  for (const auto& [key, value] : strings)
    if (const Json* v = r.find(j, key, key, false)) *value = r.string(*v, key);
  if (const Json* v = r.find(j, "options", "options", false)) p.options = read_options(r, *v);
  if (const Json* v = r.find(j, "stock", "stock", need(kPartStock)))
    p.metadata.stock = read_stock(r, *v);
  if (const Json* v = r.find(j, "tools", "tools", need(kPartTools)))
    p.metadata.tools = read_tools(r, *v);
  const Json* surfaces = r.find(j, "surfaces", "surfaces", need(kPartSurfaces));
  if (surfaces) p.metadata.surfaces = read_surfaces(r, *surfaces);
  if (const Json* v = r.find(j, "operations", "operations", need(kPartOperations)))
    p.metadata.operations = read_operations(r, *v);
  if (const Json* v = r.find(j, "rotary_travel_deg", "rotary_travel_deg", false))
    read_rotary_travel(r, *v, p.metadata);
  if (const Json* v = r.find(j, "mesh", "mesh", false)) p.mesh = read_mesh(r, *v);
  if (const Json* v = r.find(j, "triangle_surface_ids", "triangle_surface_ids",
                             need(kPartTriangleSurfaceIds))) {
    p.triangle_surface_ids = read_ids(r, *v, "triangle_surface_ids");
    if (surfaces) {
      for (std::size_t i = 0; i < p.triangle_surface_ids.size(); ++i) {
        const int id = p.triangle_surface_ids[i];
        if (!p.surface(id))
          r.fail(at("triangle_surface_ids", i),
                 "surface " + std::to_string(id) + " is not in surfaces");
      }
    }
  }
  // Physical sense, for every reader of part.json (cmm, field and demo as
  // well as the machining): millimetres, tools that can cut, stock on a
  // machine. Checked on what was read; absent lists pass.
  check_part_file_sense(p, name);
  return p;
}

PartFile read_part_file(const std::filesystem::path& file, unsigned required) {
  std::string text;
  try {
    text = rt::read_input_file(file, "part file");
  } catch (const rt::InputFileError& e) {
    throw PartFileError(file.string(), "", e.reason());
  }
  return parse_part_file(text, file.string(), required);
}

}  // namespace truecut::sim
