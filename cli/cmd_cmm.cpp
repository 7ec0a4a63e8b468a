// truecut cmm MESH --out cmm.csv: the virtual CMM probes nominal points on a
// machined mesh and prints per-surface deviation statistics.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include "args.hpp"
#include "commands.hpp"
#include "truecut/offline/mesh_io.hpp"
#include "truecut/sim/measure/cmm.hpp"
#include "truecut/sim/measure/part_surfaces.hpp"

namespace truecut::cli {
namespace {

const char* kCmmHelp =
    "usage: truecut cmm MESH --nominal NOMINAL.stl --part PART.json [--surfaces 1,2]\n"
    "                        [--spacing MM] --out CMM.csv [options]\n"
    "       truecut cmm MESH --points POINTS.csv --out CMM.csv [options]\n"
    "\n"
    "Probes nominal points along their nominal normals on MESH (the machined\n"
    "surface, workpiece frame, mm) and writes CMM.csv with the header\n"
    "x,y,z,nx,ny,nz,surface,deviation_mm,valid (deviation > 0: material outside the\n"
    "nominal surface). Points come from an even sampling of the nominal surfaces\n"
    "(default: those part.json marks compensate) or from POINTS.csv\n"
    "(x y z nx ny nz [surface]). Prints RMS, max |dev|, P95 |dev|, mean and std dev\n"
    "per surface in um. Model: docs/measurement.md.\n"
    "\n"
    "options:\n"
    "  --out FILE          CSV of the probed points\n"
    "  --nominal FILE      nominal mesh (nominal.stl of `truecut part`)\n"
    "  --part FILE         part.json with the surface id of every nominal triangle\n"
    "  --surfaces LIST     surface ids to probe, comma-separated\n"
    "  --spacing MM        distance between probed points (default 1.0)\n"
    "  --points FILE       probe these points instead\n"
    "  --sigma-um S        probing noise, 0..20 um (default 2)\n"
    "  --search-mm D       search distance along the normal each way (default 1.0)\n"
    "  --seed N            noise seed (default 1)\n"
    "  --help              this text\n";

std::vector<std::int32_t> parse_surface_list(const std::string& text) {
  std::vector<std::int32_t> ids;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = std::min(text.find(',', start), text.size());
    const std::string item = text.substr(start, comma - start);
    char* end = nullptr;
    const long v = std::strtol(item.c_str(), &end, 10);
    if (item.empty() || *end != '\0' || v < -2147483647L || v > 2147483647L)
      throw UsageError("--surfaces '" + text + "': '" + item + "' is not a surface id");
    ids.push_back(static_cast<std::int32_t>(v));
    start = comma + 1;
  }
  return ids;
}

void print_row(const sim::measure::SurfaceDeviationStats& s) {
  const std::string name = s.surface < 0 ? "all" : std::to_string(s.surface);
  std::printf("%-8s %7zu %7zu %9.2f %9.2f %9.2f %9.2f %9.2f\n", name.c_str(), s.points, s.valid,
              s.mean_um, s.std_um, s.rms_um, s.max_abs_um, s.p95_abs_um);
}

int input_error(const std::string& message) {
  std::fprintf(stderr, "truecut cmm: %s\n", message.c_str());
  return kExitUsage;
}

// Outputs are written to NAME.tmp and renamed: never over a device, FIFO or folder.
void require_replaceable(const std::string& file) {
  std::error_code ec;
  const auto status = std::filesystem::status(file, ec);
  if (std::filesystem::exists(status) && !std::filesystem::is_regular_file(status))
    throw UsageError(file + " exists and is not a regular file");
}

}  // namespace

int cmd_cmm(const std::vector<std::string>& argv) {
  ParsedArgs a(argv, {{"out", true},
                      {"nominal", true},
                      {"part", true},
                      {"surfaces", true},
                      {"spacing", true},
                      {"points", true},
                      {"sigma-um", true},
                      {"search-mm", true},
                      {"seed", true},
                      {"help", false}});
  if (a.flag("help")) {
    std::fputs(kCmmHelp, stdout);
    return kExitOk;
  }
  if (a.positionals().size() != 1) throw UsageError("expected one MESH file (the machined part)");
  const std::string mesh_file = a.positionals()[0];
  const auto out = a.value("out");
  if (!out) throw UsageError("--out FILE is required");
  const auto points_file = a.value("points");
  const auto nominal_file = a.value("nominal");
  const auto part_file = a.value("part");
  if (points_file && (nominal_file || part_file || a.value("surfaces") || a.value("spacing")))
    throw UsageError("--points excludes --nominal, --part, --surfaces and --spacing");
  if (!points_file && !(nominal_file && part_file))
    throw UsageError("give --nominal and --part, or --points");
  require_replaceable(*out);
  sim::measure::CmmOptions opt;
  opt.sigma_mm = a.number("sigma-um", 2.0, 0.0, 20.0) / 1000.0;
  opt.search_distance_mm = a.number("search-mm", opt.search_distance_mm, 1e-3, 100.0);
  opt.seed = static_cast<std::uint64_t>(a.integer("seed", 1, 0, 0x7fffffffffffffffL));
  const double spacing_mm = a.number("spacing", 1.0, 0.01, 1000.0);
  std::vector<std::int32_t> surfaces;
  if (const auto list = a.value("surfaces")) surfaces = parse_surface_list(*list);

  offline::TriangleMesh machined;
  std::vector<sim::measure::CmmPoint> points;
  try {
    machined = offline::read_mesh(mesh_file);
    if (machined.triangles.empty()) return input_error(mesh_file + ": no triangles");
    if (points_file) {
      points = sim::measure::read_cmm_points(*points_file);
    } else {
      const offline::TriangleMesh nominal = offline::read_mesh(*nominal_file);
      const sim::measure::PartSurfaces labels = sim::measure::read_part_surfaces(*part_file);
      if (labels.triangle_surface_ids.size() != nominal.triangles.size())
        return input_error(*part_file + ": key 'triangle_surface_ids' has " +
                           std::to_string(labels.triangle_surface_ids.size()) + " entries but " +
                           *nominal_file + " has " + std::to_string(nominal.triangles.size()) +
                           " triangles");
      for (std::int32_t id : surfaces)
        if (!labels.has(id))
          return input_error(*part_file + ": key 'surfaces' has no surface " + std::to_string(id));
      if (surfaces.empty()) surfaces = labels.compensated_ids();
      points = sim::measure::cmm_points_on_surfaces(nominal, labels.triangle_surface_ids,
                                                    spacing_mm, surfaces);
      if (points.empty())
        return input_error(*nominal_file + ": no points on the selected surfaces");
    }
  } catch (const offline::MeshIoError& e) {
    return input_error(e.what());
  } catch (const sim::measure::CmmInputError& e) {
    return input_error(e.what());
  } catch (const sim::measure::PartFileError& e) {
    return input_error(e.what());
  }

  std::fprintf(stderr, "cmm: probing %zu points on %s\n", points.size(), mesh_file.c_str());
  const auto measurements = sim::measure::probe(machined, points, opt);
  sim::measure::write_cmm_csv(*out, measurements);

  const auto overall = sim::measure::overall_statistics(measurements);
  std::printf("%-8s %7s %7s %9s %9s %9s %9s %9s\n", "surface", "points", "valid", "mean_um",
              "std_um", "rms_um", "max_um", "p95_um");
  for (const auto& s : sim::measure::surface_statistics(measurements))
    print_row(s);
  print_row(overall);
  if (overall.valid < overall.points)
    std::fprintf(
        stderr, "cmm: %zu of %zu points found no surface within %.3f mm (valid = 0 in %s)\n",
        overall.points - overall.valid, overall.points, opt.search_distance_mm, out->c_str());
  return kExitOk;
}

namespace {
const CommandRegistration kRegistration{
    "cmm", "virtual CMM: probe nominal points on a machined mesh", cmd_cmm, 35};
}  // namespace

}  // namespace truecut::cli
