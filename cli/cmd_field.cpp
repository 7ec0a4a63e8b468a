// truecut field NOMINAL.stl SCAN --program PART.ngc --tools TOOLS.tbl --out DIR:
// the offline chain from a scan to a correction field (docs/offline.md,
// "truecut field").

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "args.hpp"
#include "commands.hpp"
#include "measure_options.hpp"
#include "parameter_file_args.hpp"
#include "program_budget_args.hpp"
#include "quiet_option.hpp"
#include "side_by_side.hpp"
#include "stage_progress.hpp"
#include "truecut/interp/error.hpp"
#include "truecut/interp/interpreter.hpp"
#include "truecut/offline/field_outputs.hpp"
#include "truecut/offline/field_pipeline.hpp"
#include "truecut/offline/mesh_io.hpp"
#include "truecut/offline/mesh_topology.hpp"
#include "truecut/rt/field_file.hpp"
#include "truecut/rt/number_format.hpp"
#include "truecut/sim/part_file.hpp"

namespace truecut::cli {
namespace {

namespace fs = std::filesystem;
using offline::ToolShape;

const char* kFieldHelp =
    "usage: truecut field NOMINAL.stl SCAN.{ply,stl,xyz,csv} --program PART.ngc\n"
    "                     --tools TOOLS.tbl --out DIR [options]\n"
    "\n"
    "Registers the scan to the nominal model, measures error vectors at the\n"
    "compensation points, mirrors and smooths them, places each one where the\n"
    "tool centre is when the program cuts that point, and fits the correction\n"
    "field (one layer per tool). Writes into DIR, all or nothing:\n"
    "  field.tcf  compensation_matrix.csv  adapted.stl  audit.json\n"
    "Progress goes to stderr, a summary to stdout. Exit codes: 0 ok; 1 refused\n"
    "(correction above --max-correction) or runtime failure; 2 usage or input\n"
    "error (the message names the file and element). On 1 or 2 DIR is untouched.\n"
    "\n"
    "inputs:\n"
    "  --program FILE        the CAM program (RS274/NGC, TRAORI for 5-axis)\n"
    "  --tools FILE          LinuxCNC tool table (D = diameter, Z = length)\n"
    "  --part FILE           part.json of a benchmark part: surface ids per\n"
    "                        triangle, compensated surfaces, tool shapes\n"
    "  --out DIR             output folder (created if missing)\n"
    "  --base FIELD.tcf      a further iteration: the field the scanned part was cut\n"
    "                        with; the new field is it plus the new compensation\n"
    "  --expected MESH       the surface the program leaves on an error-free machine\n"
    "                        (STL/PLY, workpiece frame; e.g. truecut run on the ideal\n"
    "                        machine): errors are measured against it, so scallops\n"
    "                        and what else the program leaves are not compensated\n"
    "options:\n"
    "  --paper sortino|denkena  every stage's default as in that source, explicit\n"
    "                        options still win (docs/offline.md, The sources' recipes).\n"
    "                        sortino (3D model adaptation): sphere method, Rs 1 mm,\n"
    "                        planes parallel to the nominal, every point and facet,\n"
    "                        rigid-body motion removed, truss of bars, kb/kc 0.2.\n"
    "                        denkena (optical-scan G-code compensation): ray method;\n"
    "                        its route continues with truecut rewrite --paper denkena\n"
    "                        on compensation_matrix.csv. Both: no significance tests\n"
    "  --method ray|sphere   error vectors: rays to a scanned mesh (default when the\n"
    "                        scan has faces) or plane fits in spheres (point clouds)\n"
    "  --spacing MM          compensation points: even sampling at this spacing\n"
    "                        (default 0 = the nominal vertices)\n"
    "  --surfaces ID,...     compensated surfaces (default: part.json's, else all)\n"
    "  --datum ID,...        register on these surfaces only (default: all)\n"
    "  --no-register         the scan is already in the workpiece frame\n"
    "  --register-significance P  apply the registration only when a motion that\n"
    "                        large arises from the scan's noise with probability\n"
    "                        below P (default 0.001; 0: always apply)\n"
    "  --max-scan-offset MM  refuse a scan (exit 2) that registration must move, or\n"
    "                        that with --no-register sits, farther than this off\n"
    "                        the nominal anywhere on the part (default 0.3)\n"
    "  --max-scan-outliers PERCENT  refuse a scan with more of its points than this\n"
    "                        farther than --max-scan-offset from the nominal after\n"
    "                        registration (default 20)\n"
    "  --tool-rotation       also fit a rotation of the tool about its tip where a\n"
    "                        flank's error changes along the tool axis (field\n"
    "                        channels rx ry rz; docs/offline.md, Tool rotation)\n"
    "  --rotary-kinematics K  what tilts the machine gives --tool-rotation: ac-table\n"
    "                        (default: a table-table A/C, whose standing tool\n"
    "                        tilts only along A) or any (every tilt)\n"
    "  --rotation-significance Z  --tool-rotation: a pass's slope must stand Z\n"
    "                        standard errors out of the scan's noise (default 2;\n"
    "                        0: every slope)\n"
    "  --remove-rbm          remove the rigid-body motion left in the error vectors\n"
    "  --sphere-radius MM    sphere method radius Rs (default 1.5)\n"
    "  --sphere-max-points N  sphere method: where the median sphere holds more scan\n"
    "                        points than N, fit on a fixed subset of the scan of\n"
    "                        about N per sphere (default 256; 0: every point, as the\n"
    "                        model-adaptation source does)\n"
    "  --sphere-max-facets N  sphere method: where the median sphere holds more\n"
    "                        nominal facets than N, the planes not through the point\n"
    "                        come from a fixed subset of about N facets per sphere\n"
    "                        (default 64; 0: every facet, as the source does)\n"
    "  --plane-fit tilted|parallel  sphere method planes: tilted (default) fits each\n"
    "                        plane's orientation too; parallel keeps the nominal's and\n"
    "                        fits only the offset, as the model-adaptation source does\n"
    "  --max-distance MM     ray method search distance each way (default 1)\n"
    "  --significance P      compensate a surface only when a surface cut exactly\n"
    "                        right would show its measured error with probability\n"
    "                        below P under the scan's noise (default 0.001; 0: every\n"
    "                        surface)\n"
    "  --scan-noise MM       the scanner's noise along the normal (default: estimated\n"
    "                        from the scan)\n"
    "  --kb-kc X             truss smoothing kb/kc (default 1, times (noise / 20 um)^2\n"
    "                        for scans noisier than 20 um; given: used as is)\n"
    "  --truss springs|bars  truss stiffness: springs (default) resist every component\n"
    "                        of the difference between neighbours; bars resist only a\n"
    "                        change of their length, as in the model-adaptation source\n"
    "                        (Sortino et al.): nothing smooths the normal of a flat face\n"
    "  --resolution MM       field grid spacing (default 1)\n"
    "  --smoothness X        field fit regularisation lambda (default 0.1)\n"
    "  --path-step MM        tool path sampling step (default 0.1)\n"
    "  --contact-tolerance MM  a tool cuts a point within this of its surface (0.05)\n"
    "  --placement every-pass|first  a point goes to every pass that cuts it as deep\n"
    "                        as the closest (default: a lower level re-sweeps the wall\n"
    "                        above it), or only to the first of them\n"
    "  --edge-exclusion MM   ray method: no error vector this close to a sharp\n"
    "                        nominal edge (default 0.5)\n"
    "  --corner-radius T=MM  corner radius of tool T (repeatable; default 0, or part.json)\n"
    "  --cutting-length T=MM cutting length of tool T (default: part.json's flute\n"
    "                        length, else the table's Z length, else 10 x radius)\n"
    "  --max-points N        budget: refuse (exit 2) a --spacing that would place more\n"
    "                        compensation points than this (default 20000000)\n"
    "  --max-grid-nodes N    budget: refuse (exit 2) a --resolution whose field grid\n"
    "                        would exceed this many nodes per layer (default 16777216)\n"
    "  --max-memory-mb N     budget: refuse (exit 2) a --spacing, --resolution or\n"
    "                        scan whose estimated memory (compensation points with\n"
    "                        their placements and sphere support lists, the scan,\n"
    "                        the field grid) exceeds N MB (default 4096)\n"
    "  --max-correction MM   refuse (exit 1) above this correction (default 0.2)\n"
    "  --force               write although the correction exceeds --max-correction\n"
    "  --strict-mesh         refuse a mesh with degenerate (zero-area) facets or facets\n"
    "                        wound against their neighbours, instead of dropping or\n"
    "                        turning them round (listed on stderr and in audit.json)\n"
    "  --verbose             each stage on stderr as it ends: its wall time, what it\n"
    "                        found and the process's peak memory so far (also in\n"
    "                        audit.json, \"stages\")\n"
    "  --quiet               nothing on stderr but warnings and errors (default: the\n"
    "                        current stage on a terminal after a second, and one\n"
    "                        line of totals)\n"
    "  --help                this text\n";

// An input error: exit 2 with the message (which names the file).
struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

std::vector<std::int32_t> id_list(const std::string& option, const std::string& text) {
  std::vector<std::int32_t> ids;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const std::size_t comma = std::min(text.find(',', pos), text.size());
    const std::string item = text.substr(pos, comma - pos);
    char* end = nullptr;
    const long v = std::strtol(item.c_str(), &end, 10);
    if (item.empty() || *end != '\0' || v < 0 || v > 1'000'000)
      throw UsageError("--" + option + ": '" + item + "' is not a surface id");
    ids.push_back(static_cast<std::int32_t>(v));
    pos = comma + 1;
  }
  return ids;
}

// "T=MM" pairs of a repeatable option; MM >= 0, or > 0 when `positive`.
std::map<int, double> tool_values(const ParsedArgs& a, const std::string& option, bool positive) {
  std::map<int, double> out;
  for (const std::string& v : a.values(option)) {
    const std::size_t eq = v.find('=');
    char *e1 = nullptr, *e2 = nullptr;
    const std::string t = v.substr(0, eq), x = eq == std::string::npos ? "" : v.substr(eq + 1);
    const long tool = std::strtol(t.c_str(), &e1, 10);
    const double mm = std::strtod(x.c_str(), &e2);
    if (eq == std::string::npos || t.empty() || x.empty() || *e1 || *e2 || tool < 0 ||
        tool > 99999 || !(mm >= 0 && mm < 1e4))
      throw UsageError("--" + option + " '" + v +
                       "': expected TOOL=MM (tool 0 to 99999, MM 0 to "
                       "10000)");
    if (positive && !(mm > 0))
      throw UsageError("--" + option + " '" + v +
                       "': must be greater than 0 mm (a tool cuts along some length)");
    out[static_cast<int>(tool)] = mm;
  }
  return out;
}

struct PartFile {
  std::vector<std::int32_t> triangle_surface_ids;
  std::vector<std::int32_t> compensated;
  std::map<int, ToolShape> tools;
};

PartFile read_part_file(const fs::path& file) {
  sim::PartFile part;
  try {
    part = sim::read_part_file(file,
                               sim::kPartTriangleSurfaceIds | sim::kPartSurfaces | sim::kPartTools);
  } catch (const sim::PartFileError& e) {
    throw InputError(e.what());
  }
  PartFile p;
  p.triangle_surface_ids.assign(part.triangle_surface_ids.begin(), part.triangle_surface_ids.end());
  for (const int id : part.compensated_surface_ids())
    p.compensated.push_back(id);
  for (const sim::PartTool& t : part.metadata.tools) {
    ToolShape s;
    s.tool = t.number;
    s.radius_mm = t.radius_mm;
    s.corner_radius_mm = t.corner_radius_mm;
    s.cutting_length_mm = t.flute_length_mm;
    p.tools[s.tool] = s;
  }
  return p;
}

std::vector<ToolShape> tool_shapes(const interp::ToolTable& table, const fs::path& table_file,
                                   const std::optional<PartFile>& part, const ParsedArgs& a) {
  const std::map<int, double> corner = tool_values(a, "corner-radius", false);
  const std::map<int, double> cutting = tool_values(a, "cutting-length", true);
  std::vector<ToolShape> shapes;
  for (const interp::ToolEntry& e : table.entries()) {
    ToolShape s;
    s.tool = e.number;
    s.radius_mm = 0.5 * e.diameter_mm;
    if (part && part->tools.count(e.number)) {
      const ToolShape& p = part->tools.at(e.number);
      s.corner_radius_mm = p.corner_radius_mm;
      s.cutting_length_mm = p.cutting_length_mm;
    }
    if (corner.count(e.number)) s.corner_radius_mm = corner.at(e.number);
    if (cutting.count(e.number)) s.cutting_length_mm = cutting.at(e.number);
    if (s.cutting_length_mm <= 0) s.cutting_length_mm = e.offset_mm.z > 0 ? e.offset_mm.z : 0;
    if (s.cutting_length_mm <= 0) s.cutting_length_mm = 10 * s.radius_mm;
    s.cutting_length_mm = std::max(s.cutting_length_mm, s.corner_radius_mm);
    if (!(s.radius_mm > 0)) continue;  // a tool without a diameter cannot be placed
    if (s.corner_radius_mm > s.radius_mm)
      throw InputError(table_file.string() + ": tool " + std::to_string(s.tool) +
                       ": corner radius " + std::to_string(s.corner_radius_mm) +
                       " mm exceeds the radius " + std::to_string(s.radius_mm) + " mm");
    shapes.push_back(s);
  }
  return shapes;
}

// Reads a mesh; degenerate (zero-area) facets are dropped and reported
// unless --strict-mesh, which refuses the file instead.
offline::TriangleMesh read_input_mesh(const fs::path& file, const std::string& role, bool strict,
                                      std::vector<offline::MeshInputAudit>& audit) {
  offline::MeshReadOptions options;
  options.degenerate_faces =
      strict ? offline::DegenerateFaces::kError : offline::DegenerateFaces::kDrop;
  offline::MeshReadReport report;
  offline::TriangleMesh mesh;
  try {
    mesh = offline::read_mesh(file, options, &report);
  } catch (const offline::MeshIoError& e) {
    std::string what = e.what();
    if (strict && what.find(" is degenerate (") != std::string::npos)
      what += "; without --strict-mesh such facets are dropped and counted";
    throw InputError(what);
  }
  std::optional<offline::MeshTopology> topology;
  if (!mesh.triangles.empty()) {
    topology = offline::orient_mesh(mesh);
    if (strict && topology->flipped_triangles > 0)
      throw InputError(file.string() + ": " + std::to_string(topology->flipped_triangles) +
                       " facets are wound against their neighbours or the solid is inside out; "
                       "without --strict-mesh they are turned round");
  }
  audit.push_back(
      {role, file, report.faces_in_file, std::move(report.dropped_triangles), topology});
  return mesh;
}

// "nominal.stl: 1 shell (0 open), 3 facets wound against ... turned round"
std::string topology_message(const offline::MeshInputAudit& m) {
  const offline::MeshTopology& t = *m.topology;
  std::string s = rt::format_printf("%s: %zu shell%s (%zu open: %zu boundary edges)",
                                    m.file.filename().string().c_str(), t.shells,
                                    t.shells == 1 ? "" : "s", t.open_shells, t.boundary_edges);
  if (t.nonmanifold_edges)
    s += rt::format_printf(", %zu non-manifold edges (more than two facets)", t.nonmanifold_edges);
  if (t.nonorientable_shells)
    s += rt::format_printf(", %zu non-orientable shells left as they are", t.nonorientable_shells);
  if (t.inverted_shells)
    s += rt::format_printf(", %zu closed shells inside out", t.inverted_shells);
  if (t.inconsistent_edges)
    s += rt::format_printf(", %zu edges between facets wound against each other",
                           t.inconsistent_edges);
  if (t.flipped_triangles)
    s += rt::format_printf("; %zu facets turned round (normals outwards)", t.flipped_triangles);
  return s;
}

// "scan.stl: dropped 2 degenerate facets of 113906: #48211 (area 3e-12 mm²), ..."
// One line instead of a line per stage (those come with --verbose).
std::string totals_message(const offline::FieldPipelineResult& r) {
  double peak_mb = 0.0;
  for (const offline::StageTime& s : r.stages)
    peak_mb = std::max(peak_mb, s.peak_rss_mb);
  return rt::format_printf("%zu stages in %.3f s wall, peak memory %.0f MB (--verbose: each stage)",
                           r.stages.size(), r.total_wall_s, peak_mb);
}

std::string dropped_message(const offline::MeshInputAudit& m) {
  const std::size_t n = m.dropped.size();
  std::string s = m.file.filename().string() + ": dropped " + std::to_string(n) +
                  " degenerate facet" + (n == 1 ? "" : "s") + " of " +
                  std::to_string(m.facets_in_file) + ":";
  constexpr std::size_t kListed = 5;
  for (std::size_t i = 0; i < std::min(n, kListed); ++i)
    s += rt::format_printf("%s #%zu (area %.3g mm², longest edge %.3g mm)", i ? "," : "",
                           m.dropped[i].face, m.dropped[i].area_mm2, m.dropped[i].longest_edge_mm);
  if (n > kListed) s += rt::format_printf(" and %zu more (all in audit.json)", n - kListed);
  return s + "; --strict-mesh refuses such a mesh instead";
}

struct Inputs {
  offline::TriangleMesh nominal, scan;
  std::optional<offline::TriangleMesh> expected;
  interp::CanonProgram program;
  interp::ToolTable tools;
  std::optional<PartFile> part;
  std::optional<rt::CorrectionField> base;
  std::vector<offline::FileDigest> digests;
  std::vector<offline::MeshInputAudit> meshes;
};

Inputs read_inputs(const ParsedArgs& a, const fs::path& program_file, const fs::path& tools_file) {
  Inputs in;
  const fs::path nominal_file = a.positionals()[0], scan_file = a.positionals()[1];
  const bool strict = a.flag("strict-mesh");
  // The two meshes and the program side by side; an error is reported for
  // the first of them in this order.
  std::vector<offline::MeshInputAudit> nominal_audit, scan_audit;
  offline::FileDigest nominal_digest, scan_digest;
  run_side_by_side({
      [&] { in.nominal = read_input_mesh(nominal_file, "nominal", strict, nominal_audit); },
      [&] { in.scan = read_input_mesh(scan_file, "scan", strict, scan_audit); },
      [&] {
        try {
          interp::InterpreterOptions io;
          io.max_blocks = max_blocks_from_args(a);
          in.tools = interp::ToolTable::load(tools_file);
          io.tools = in.tools;
          if (auto p = parameter_file_from_args(a)) io.parameters = std::move(*p);
          in.program = interp::Interpreter(std::move(io)).run_file(program_file);
        } catch (const interp::GcodeError& e) {
          throw InputError(e.what());
        }
      },
  });
  // Hashed only once read: a file the readers refuse (a device, an endless
  // stream) is never read to its end.
  run_side_by_side({
      [&] { nominal_digest = offline::digest_file("nominal", nominal_file); },
      [&] { scan_digest = offline::digest_file("scan", scan_file); },
  });
  in.meshes = std::move(nominal_audit);
  in.meshes.insert(in.meshes.end(), std::make_move_iterator(scan_audit.begin()),
                   std::make_move_iterator(scan_audit.end()));
  if (auto p = a.value("part")) in.part = read_part_file(*p);
  in.digests.push_back(std::move(nominal_digest));
  in.digests.push_back(std::move(scan_digest));
  for (std::size_t i = 0; i < in.program.files.size(); ++i)
    in.digests.push_back(
        offline::digest_file(i == 0 ? "program" : "subroutine", in.program.files[i]));
  in.digests.push_back(offline::digest_file("tools", tools_file));
  if (auto v = a.value("var-file")) in.digests.push_back(offline::digest_file("parameters", *v));
  if (auto p = a.value("part")) in.digests.push_back(offline::digest_file("part", *p));
  if (auto e = a.value("expected")) {
    in.expected = read_input_mesh(*e, "expected", strict, in.meshes);
    if (in.expected->triangles.empty())
      throw InputError(*e + ": the expected cut must be a mesh with faces");
    in.digests.push_back(offline::digest_file("expected", *e));
  }
  if (auto b = a.value("base")) {
    try {
      in.base = rt::read_field_file(*b).field;
    } catch (const std::exception& e) {
      throw InputError(e.what());
    }
    in.digests.push_back(offline::digest_file("base_field", *b));
  }
  return in;
}

offline::FieldPipelineOptions pipeline_options(const ParsedArgs& a, const Inputs& in) {
  offline::FieldPipelineOptions o;
  // --paper: every stage's default as in that source (docs/offline.md,
  // "The sources' recipes"); an option given explicitly still wins.
  const std::string paper = a.value("paper").value_or("");
  if (!paper.empty() && paper != "sortino" && paper != "denkena")
    throw UsageError("--paper must be sortino or denkena, not '" + paper + "'");
  const bool sortino = paper == "sortino", denkena = paper == "denkena";
  if (sortino) {
    o.sphere.radius_mm = 1.0;
    o.sphere.max_points_per_sphere = 0;
    o.sphere.max_facets_per_sphere = 0;
    o.truss.kb_over_kc = 0.2;
  }
  const std::string method = a.value("method").value_or(sortino                     ? "sphere"
                                                        : denkena                   ? "ray"
                                                        : in.scan.triangles.empty() ? "sphere"
                                                                                    : "ray");
  if (method == "ray") {
    o.method = offline::ErrorMethod::kRay;
  } else if (method == "sphere") {
    o.method = offline::ErrorMethod::kSphere;
  } else {
    throw UsageError("--method must be ray or sphere, not '" + method + "'");
  }
  if (o.method == offline::ErrorMethod::kRay && in.scan.triangles.empty())
    throw InputError(a.positionals()[1] +
                     ": the scan has no faces; the ray method needs a mesh (use --method sphere)");
  o.spacing_mm = a.number("spacing", 0.0, 0.0, 100.0);
  if (auto s = a.value("surfaces")) {
    o.surfaces = id_list("surfaces", *s);
  } else if (in.part) {
    o.surfaces = in.part->compensated;
  }
  if (auto d = a.value("datum")) o.datum_surfaces = id_list("datum", *d);
  o.register_scan = !a.flag("no-register");
  if (!o.register_scan && a.value("register-significance"))
    throw UsageError(
        "--register-significance tests a registration, and --no-register makes none; give one");
  // Neither source tests the registration or a surface's error against the
  // scan's noise: both apply what they find.
  o.icp.significance_level =
      a.number("register-significance", paper.empty() ? 0.001 : 0.0, 0.0, 0.5);
  o.scan_check.max_offset_mm =
      a.number("max-scan-offset", o.scan_check.max_offset_mm, 1e-3, 1000.0);
  o.scan_check.max_off_percent =
      a.number("max-scan-outliers", o.scan_check.max_off_percent, 0.0, 100.0);
  o.remove_rigid_body_motion = a.flag("remove-rbm") || sortino;
  o.tool_rotation = a.flag("tool-rotation");
  o.rotation.min_slope_significance =
      a.number("rotation-significance", o.rotation.min_slope_significance, 0.0, 10.0);
  if (auto k = a.value("rotary-kinematics")) {
    if (*k == "ac-table")
      o.rotation.kinematics = offline::RotaryKinematics::kAcTableTable;
    else if (*k == "any")
      o.rotation.kinematics = offline::RotaryKinematics::kAnyOrientation;
    else
      throw UsageError("--rotary-kinematics must be ac-table or any, not '" + *k + "'");
  }
  o.sphere.radius_mm = a.number("sphere-radius", o.sphere.radius_mm, 0.01, 100.0);
  o.sphere.max_points_per_sphere = static_cast<std::size_t>(a.integer(
      "sphere-max-points", static_cast<long>(o.sphere.max_points_per_sphere), 0, 100000000));
  o.sphere.max_facets_per_sphere = static_cast<std::size_t>(a.integer(
      "sphere-max-facets", static_cast<long>(o.sphere.max_facets_per_sphere), 0, 100000000));
  const std::string plane_fit = a.value("plane-fit").value_or(sortino ? "parallel" : "tilted");
  if (plane_fit != "tilted" && plane_fit != "parallel")
    throw UsageError("--plane-fit must be tilted or parallel, not '" + plane_fit + "'");
  o.sphere.tilted_planes = plane_fit == "tilted";
  o.ray.max_distance_mm = a.number("max-distance", o.ray.max_distance_mm, 0.001, 100.0);
  o.significance.significance_level =
      a.number("significance", paper.empty() ? o.significance.significance_level : 0.0, 0.0, 0.5);
  // Absent: estimated from the scan; given, it is the scanner's noise (> 0).
  o.significance.noise_mm = a.value("scan-noise") ? a.number("scan-noise", 0.0, 1e-6, 10.0) : 0.0;
  o.truss.kb_over_kc = a.number("kb-kc", o.truss.kb_over_kc, 0.0, 1e6);
  // A kb/kc given is used as given; the default scales with the scan's noise.
  if (a.value("kb-kc") || sortino) o.truss_reference_noise_mm = 0.0;
  const std::string truss = a.value("truss").value_or(sortino ? "bars" : "springs");
  if (truss != "springs" && truss != "bars")
    throw UsageError("--truss must be springs or bars, not '" + truss + "'");
  o.truss.stiffness = truss == "bars" ? offline::TrussStiffness::kAxialBars
                                      : offline::TrussStiffness::kZeroLengthSprings;
  o.fit.spacing_mm = a.number("resolution", o.fit.spacing_mm, 0.05, 100.0);
  o.fit.smoothness = a.number("smoothness", o.fit.smoothness, 0.0, 1e6);
  o.max_compensation_points = a.number("max-points", o.max_compensation_points, 1.0, 1e12);
  o.max_grid_nodes = a.number("max-grid-nodes", o.max_grid_nodes, 8.0, 1e12);
  o.max_memory_mb = a.number("max-memory-mb", o.max_memory_mb, 1.0, 1e9);
  o.path.step_mm = a.number("path-step", o.path.step_mm, 0.001, 10.0);
  o.placement.contact_tolerance_mm =
      a.number("contact-tolerance", o.placement.contact_tolerance_mm, 1e-6, 10.0);
  const std::string placement = a.value("placement").value_or("every-pass");
  if (placement != "first" && placement != "every-pass")
    throw UsageError("--placement " + placement + ": expected first or every-pass");
  o.placement.every_generating_pass = placement == "every-pass";
  o.ray.edge_exclusion_mm = a.number("edge-exclusion", o.ray.edge_exclusion_mm, 0.0, 100.0);
  return o;
}

void print_summary(const offline::FieldPipelineResult& r,
                   const std::vector<offline::FileDigest>& out, bool forced) {
  if (r.registration && !r.registration->applied)
    std::printf(
        "registration: not applied, the motion found is within the scan's noise (chi2 %.1f <= "
        "%.1f); RMS residual %.4f mm\n",
        r.registration->motion_chi2, r.registration->motion_threshold,
        r.registration->rms_after_mm);
  else if (r.registration) {
    const offline::RigidTransformReport& t = r.registration->transform;
    constexpr double kUradPerDeg = 1e6 * 3.14159265358979323846 / 180.0;
    std::printf(
        "registration: %d iterations, RMS residual %.4f mm; it removed translation %.1f %.1f "
        "%.1f um, rotation %.1f %.1f %.1f urad (about x, y, z), up to %.1f um on the part\n",
        r.registration->iterations, r.registration->rms_after_mm, 1e3 * t.translation_mm.x(),
        1e3 * t.translation_mm.y(), 1e3 * t.translation_mm.z(),
        kUradPerDeg * t.rotation_xyz_deg.x(), kUradPerDeg * t.rotation_xyz_deg.y(),
        kUradPerDeg * t.rotation_xyz_deg.z(), 1e3 * r.registration_max_displacement_mm);
  }
  if (r.registration_absorbed_beyond_noise)
    std::fprintf(stderr,
                 "truecut field: WARNING: registration on all faces moved the scan by up to %.1f "
                 "um, more than the scan's noise (%.1f um): a rigid part of the machined "
                 "error (a side cut long or short) may have been fitted away with the "
                 "misplacement. Register on the faces that define the part's frame (fixture "
                 "references) with --datum ID,...\n",
                 1e3 * r.registration_max_displacement_mm, 1e3 * r.significance.pooled_noise_mm);
  const auto& e = r.error_statistics;
  std::printf(
      "error vectors: %zu points, %.1f %% invalid, mean %.4f mm, RMS %.4f mm, max %.4f mm\n",
      e.points, e.percent_invalid, e.mean_length_mm, e.rms_length_mm, e.max_length_mm);
  for (const auto& s : r.significance.surfaces)
    std::printf(
        "surface %d: %zu points from %zu scan points, mean error %+.4f mm +- %.4f mm (noise %.4f "
        "mm%s), chi2 %.1f over %zu patches (limit %.1f): %s\n",
        s.surface, s.valid_points, s.scan_points, s.mean_normal_mm, s.mean_uncertainty_mm,
        s.noise_mm, s.pooled_noise ? ", pooled" : "", s.chi2, s.patches, s.threshold,
        !r.significance.tested ? "compensated (not tested)"
        : s.compensated        ? "compensated"
                               : "within the scan noise, not compensated");
  const auto& c = r.compensation_statistics;
  std::printf("compensation (smoothed): RMS %.4f mm, max %.4f mm; max correction %.4f mm%s\n",
              c.rms_length_mm, c.max_length_mm, r.max_correction_mm, forced ? " (FORCED)" : "");
  for (const auto& l : r.fit->layers)
    std::printf("layer T%d: %lld samples, residual RMS %.4f mm, max %.4f mm\n", l.tool,
                static_cast<long long>(l.valid_samples), l.residual_rms_mm, l.residual_max_mm);
  std::printf("points cut by no tool: %lld of %zu\n",
              static_cast<long long>(r.placement.uncut_points), r.points.size());
  for (const auto& d : out)
    std::printf("wrote %s (%ju bytes, sha256 %.16s...)\n", d.path.string().c_str(), d.bytes,
                d.sha256.c_str());
  std::printf("total %.3f s\n", r.total_wall_s);
}

// Every file written into DIR against every input, by identity (links
// included): `--base DIR/field.tcf --out DIR`, the natural next iteration,
// replaced the base field.
void refuse_outputs_over_inputs(const ParsedArgs& a, const std::string& out) {
  std::vector<std::optional<std::string>> inputs = {a.positionals()[0], a.positionals()[1]};
  for (const char* option : {"program", "tools", "part", "base", "expected", "var-file"})
    inputs.push_back(a.value(option));
  for (const char* name : offline::kFieldOutputFiles)
    refuse_output_over_input("out", (fs::path(out) / name).string(), inputs);
}

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

int run_field(const ParsedArgs& a, const std::vector<std::string>& argv) {
  if (a.positionals().size() != 2) throw UsageError("expected NOMINAL and SCAN files");
  const auto program = a.value("program"), tools = a.value("tools"), out = a.value("out");
  if (!program) throw UsageError("--program FILE is required");
  if (!tools) throw UsageError("--tools FILE is required");
  if (!out) throw UsageError("--out DIR is required");
  const double max_correction =
      a.number("max-correction", offline::kFieldMaxCorrectionMm, 0.0, 100.0);
  const bool quiet = a.flag("quiet");
  const bool verbose = a.flag("verbose") && !quiet;
  if (a.flag("verbose") && quiet) throw UsageError("--verbose and --quiet exclude each other");
  // Options checked before the inputs, which may take a while to read.
  (void)max_blocks_from_args(a);
  (void)tool_values(a, "corner-radius", false);
  (void)tool_values(a, "cutting-length", true);
  refuse_outputs_over_inputs(a, *out);
  require_writable_folder("out", *out);
  std::optional<StageProgress> shown;
  shown.emplace("truecut field", progress_shown(a));
  shown->stage("reading the inputs");

  const auto t_read = std::chrono::steady_clock::now();
  Inputs in = read_inputs(a, *program, *tools);
  if (verbose)
    std::fprintf(stderr, "field: %-34s %8.3f s  %zu nominal facets, %zu scan points\n",
                 "reading and hashing the inputs", seconds_since(t_read),
                 in.nominal.triangles.size(), in.scan.vertices_mm.size());
  const offline::FieldPipelineOptions options = pipeline_options(a, in);
  offline::FieldPipelineInputs pin;
  pin.nominal = &in.nominal;
  pin.scan = &in.scan;
  pin.program = &in.program;
  pin.tools = tool_shapes(in.tools, *tools, in.part, a);
  if (in.base) {
    pin.base_field = &*in.base;
    pin.base_field_name = "--base " + *a.value("base");
  }
  if (in.expected) pin.expected = &*in.expected;
  if (in.part) {
    // part.json numbers the triangles of the file, dropped ones included.
    const auto& dropped = in.meshes.front().dropped;
    auto& ids = in.part->triangle_surface_ids;
    if (!dropped.empty() && ids.size() == in.nominal.triangles.size() + dropped.size())
      for (auto d = dropped.rbegin(); d != dropped.rend(); ++d)
        ids.erase(ids.begin() + static_cast<std::ptrdiff_t>(d->triangle));
    if (in.part->triangle_surface_ids.size() != in.nominal.triangles.size())
      throw InputError(*a.value("part") + ": " +
                       std::to_string(in.part->triangle_surface_ids.size()) +
                       " triangle_surface_ids for " + std::to_string(in.nominal.triangles.size()) +
                       " triangles in " + a.positionals()[0]);
    pin.triangle_surface_ids = in.part->triangle_surface_ids;
  }
  // Stages of the two chains end concurrently; the pipeline serialises the calls.
  auto progress = [verbose, &shown](const std::string& stage, double s, const std::string& detail) {
    shown->stage(stage + " done");
    if (verbose)
      std::fprintf(stderr, "field: %-34s %8.3f s  %s\n", stage.c_str(), s, detail.c_str());
  };
  for (const offline::MeshInputAudit& m : in.meshes) {
    if (!m.dropped.empty()) std::fprintf(stderr, "field: %s\n", dropped_message(m).c_str());
    // A scan mesh is an open surface by nature; a nominal should be clean.
    const bool report =
        m.topology && (m.topology->flipped_triangles > 0 || m.topology->nonmanifold_edges > 0 ||
                       (m.role != "scan" && m.topology->open_shells > 0));
    if (report) std::fprintf(stderr, "field: %s\n", topology_message(m).c_str());
  }
  offline::FieldPipelineResult result;
  try {
    result = offline::run_field_pipeline(pin, options, progress);
  } catch (const std::invalid_argument& e) {
    throw InputError(e.what());
  } catch (const offline::ScanMismatchError& e) {
    throw InputError(a.positionals()[1] + ": " + e.what() + "; nothing written");
  }
  shown.reset();
  if (!quiet) std::fprintf(stderr, "field: %s\n", totals_message(result).c_str());
  if (result.base_samples_outside > 0)
    std::fprintf(stderr,
                 "truecut field: WARNING: %zu of the %zu tool centres that cut the compensated "
                 "surfaces lie outside the grid of --base %s; they get the new increment alone\n",
                 result.base_samples_outside, result.base_samples, a.value("base")->c_str());

  const bool exceeded = result.max_correction_mm > max_correction;
  if (exceeded && !a.flag("force")) {
    std::fprintf(stderr,
                 "truecut field: the correction reaches %.4f mm, above --max-correction %.4f mm; "
                 "nothing written (--force writes it and records that in audit.json)\n",
                 result.max_correction_mm, max_correction);
    return kExitFailure;
  }
  offline::AuditContext ctx;
  ctx.inputs = in.digests;
  ctx.meshes = in.meshes;
  ctx.command_line.push_back("truecut");
  ctx.command_line.push_back("field");
  ctx.command_line.insert(ctx.command_line.end(), argv.begin(), argv.end());
  ctx.tools = pin.tools;
  ctx.max_correction_limit_mm = max_correction;
  ctx.forced = exceeded;
  const auto t_write = std::chrono::steady_clock::now();
  const auto written = offline::write_field_outputs(*out, result, options, ctx);
  if (verbose)
    std::fprintf(stderr, "field: %-34s %8.3f s  %zu files\n", "writing the outputs",
                 seconds_since(t_write), written.size());
  if (exceeded)
    std::fprintf(stderr,
                 "truecut field: WARNING: correction %.4f mm above %.4f mm, written (--force)\n",
                 result.max_correction_mm, max_correction);
  print_summary(result, written, exceeded);
  return kExitOk;
}

}  // namespace

int cmd_field(const std::vector<std::string>& argv) {
  ParsedArgs a(argv, {{"program", true},
                      {"tools", true},
                      {"part", true},
                      {"out", true},
                      {"method", true},
                      {"paper", true},
                      {"spacing", true},
                      {"surfaces", true},
                      {"datum", true},
                      {"no-register", false},
                      {"remove-rbm", false},
                      {"tool-rotation", false},
                      {"rotary-kinematics", true},
                      {"rotation-significance", true},
                      {"max-scan-offset", true},
                      {"max-points", true},
                      {"max-grid-nodes", true},
                      {"max-memory-mb", true},
                      {"max-scan-outliers", true},
                      {"sphere-radius", true},
                      {"sphere-max-points", true},
                      {"sphere-max-facets", true},
                      {"plane-fit", true},
                      {"max-distance", true},
                      {"kb-kc", true},
                      {"truss", true},
                      {"significance", true},
                      {"scan-noise", true},
                      {"expected", true},
                      {"register-significance", true},
                      {"resolution", true},
                      {"smoothness", true},
                      {"path-step", true},
                      {"contact-tolerance", true},
                      {"placement", true},
                      {"edge-exclusion", true},
                      {"corner-radius", true, true},
                      {"cutting-length", true, true},
                      {"max-correction", true},
                      {"force", false},
                      {"base", true},
                      {"quiet", false},
                      {"verbose", false},
                      {"strict-mesh", false},
                      {"var-file", true},
                      {"var-units", true},
                      {"max-blocks", true},
                      {"help", false}});
  if (a.flag("help")) {
    std::fputs((std::string(kFieldHelp) + kMaxBlocksHelp + kVarFileHelp).c_str(), stdout);
    return kExitOk;
  }
  try {
    return run_field(a, argv);
  } catch (const InputError& e) {
    std::fprintf(stderr, "truecut field: %s\n", e.what());
    return kExitUsage;
  }
}

namespace {
const CommandRegistration kRegistration{
    "field", "scan + nominal + program -> correction field, matrix, adapted STL, audit", cmd_field,
    40};
}  // namespace

}  // namespace truecut::cli
