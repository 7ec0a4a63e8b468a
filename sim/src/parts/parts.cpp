#include <cmath>
#include <stdexcept>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "parts/part_builders.hpp"
#include "parts/program_writer.hpp"
#include "truecut/offline/stl_io.hpp"
#include "truecut/rt/atomic_write.hpp"

namespace truecut::sim {

std::string_view part_name(PartId id) {
  switch (id) {
    case PartId::kImplant:
      return "implant";
    case PartId::kBenchmark004:
      return "benchmark004";
    case PartId::kFreeform:
      return "freeform";
  }
  return "?";
}

std::optional<PartId> part_from_name(std::string_view name) {
  for (PartId id : kAllParts) {
    if (part_name(id) == name) return id;
  }
  return std::nullopt;
}

namespace parts {

void start_program(ProgramWriter& w, const PartMetadata& m) {
  w.line("%");
  w.comment("truecut benchmark part: " + m.name);
  w.comment(m.frame);
  w.comment("units mm; programmed points are the tool tip in the workpiece frame");
  w.line("G21 G17 G40 G49 G80 G90 G94");
  w.line("G54");
  w.line("G64 P0.005");
}

void change_tool(ProgramWriter& w, const PartTool& tool, double rpm) {
  w.line("T" + std::to_string(tool.number) + " M6");
  w.line("G43 H" + std::to_string(tool.number));
  w.line("S" + number(rpm, 0) + " M3");
  w.line("M8");
}

void end_program(ProgramWriter& w) {
  w.line("M9");
  w.line("M5");
  w.line("G49");
  w.line("M30");
  w.line("%");
}

}  // namespace parts

namespace {

void check_options(const PartOptions& o) {
  const auto ok = [](double v, double max_mm) {
    return std::isfinite(v) && v >= kMinPartOptionMm && v <= max_mm;
  };
  if (!ok(o.mesh_edge_mm, kMaxMeshEdgeMm) || !ok(o.stepover_mm, kMaxStepoverMm) ||
      !ok(o.point_spacing_mm, kMaxPointSpacingMm) || !ok(o.step_down_mm, kMaxStepDownMm)) {
    throw std::invalid_argument(
        "PartOptions: mesh_edge_mm (≤ 20), stepover_mm, point_spacing_mm (≤ 10) and "
        "step_down_mm (≤ 17) must be at least 0.001 mm");
  }
}

nlohmann::ordered_json vec(const Eigen::Vector3d& v) {
  return {v.x(), v.y(), v.z()};
}

}  // namespace

BenchmarkPart make_part(PartId id, const PartOptions& options) {
  check_options(options);
  switch (id) {
    case PartId::kImplant:
      return parts::make_implant(options);
    case PartId::kBenchmark004:
      return parts::make_benchmark004(options);
    case PartId::kFreeform:
      return parts::make_freeform(options);
  }
  throw std::invalid_argument("unknown PartId");
}

BenchmarkPart make_part(PartId id, const PartOptions& options, const DriveSurface& drive) {
  check_options(options);
  if (id != PartId::kBenchmark004)
    throw std::invalid_argument(std::string(part_name(id)) +
                                ": only benchmark004's tool path can be driven by an adapted "
                                "geometry so far");
  return parts::make_benchmark004(options, &drive);
}

std::string tool_table_text(const PartMetadata& m) {
  std::string out;
  int pocket = 1;
  for (const PartTool& t : m.tools) {
    out += "T" + std::to_string(t.number) + " P" + std::to_string(pocket++) + " D" +
           parts::number(2 * t.radius_mm, 3) + " Z" + parts::number(t.length_mm, 3) + " ;" +
           t.comment + "\n";
  }
  return out;
}

std::string part_json(const BenchmarkPart& part) {
  const PartMetadata& m = part.metadata;
  nlohmann::ordered_json j;
  j["truecut_part"] = 1;
  j["name"] = m.name;
  j["units"] = "mm";
  j["frame"] = m.frame;
  j["material"] = m.material;
  j["programmed_point"] = "tool tip";
  j["options"] = {{"mesh_edge_mm", part.options.mesh_edge_mm},
                  {"stepover_mm", part.options.stepover_mm},
                  {"point_spacing_mm", part.options.point_spacing_mm},
                  {"step_down_mm", part.options.step_down_mm}};
  for (const StockBox& b : m.stock) {
    j["stock"].push_back({{"min_mm", vec(b.min_mm)}, {"max_mm", vec(b.max_mm)}});
  }
  for (const PartTool& t : m.tools) {
    j["tools"].push_back({{"number", t.number},
                          {"kind", t.kind},
                          {"radius_mm", t.radius_mm},
                          {"corner_radius_mm", t.corner_radius_mm},
                          {"length_mm", t.length_mm},
                          {"flute_length_mm", t.flute_length_mm},
                          {"flutes", t.flutes},
                          {"comment", t.comment}});
  }
  for (const PartSurface& s : m.surfaces) {
    j["surfaces"].push_back(
        {{"id", s.id}, {"name", s.name}, {"kind", s.kind}, {"compensate", s.compensate}});
  }
  for (const PartOperation& o : m.operations) {
    j["operations"].push_back({{"name", o.name},
                               {"tool", o.tool},
                               {"strategy", o.strategy},
                               {"surface_ids", o.surface_ids}});
  }
  j["rotary_travel_deg"] = {{"a", {m.a_min_deg, m.a_max_deg}}, {"c", "unlimited"}};
  j["mesh"] = {{"file", "nominal.stl"},
               {"vertices", part.mesh.vertices_mm.size()},
               {"triangles", part.mesh.triangles.size()},
               {"volume_mm3", signed_volume_mm3(part.mesh)}};
  j["triangle_surface_ids"] = part.triangle_surface;
  return j.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) + "\n";
}

void write_part(const BenchmarkPart& part, const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  // All six or none: staged beside their targets, renamed once all are
  // written (an error or a signal on the way leaves the folder as it was).
  rt::StagedFiles files({dir / "nominal.stl", dir / "program.ngc", dir / "tools.tbl",
                         dir / "part.json", dir / "machine.json", dir / "machine_ideal.json"});
  offline::write_stl(files.staged(0), part.mesh, offline::StlEncoding::kBinary,
                     "truecut nominal " + part.metadata.name + ", workpiece frame, mm");
  files.write(1, part.program);
  files.write(2, tool_table_text(part.metadata));
  files.write(3, part_json(part));
  write_machine_description(files.staged(4), part_machine(part));
  write_machine_description(files.staged(5), part_machine_ideal(part));
  files.commit();
}

double signed_volume_mm3(const offline::TriangleMesh& mesh) {
  double six_v = 0;
  for (const auto& t : mesh.triangles) {
    const auto& a = mesh.vertices_mm[t[0]];
    const auto& b = mesh.vertices_mm[t[1]];
    const auto& c = mesh.vertices_mm[t[2]];
    six_v += a.dot(b.cross(c));
  }
  return six_v / 6.0;
}

}  // namespace truecut::sim
