// truecut cmm MESH --out cmm.csv: the virtual CMM probes nominal points on a
// machined mesh and prints per-surface deviation statistics.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "args.hpp"
#include "commands.hpp"
#include "measure_options.hpp"
#include "quiet_option.hpp"
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
    "per surface in um (\"-\" for a surface no probe found). When no probe finds the\n"
    "surface the measurement has failed: exit 1, nothing written. Model:\n"
    "docs/measurement.md.\n"
    "\n"
    "options:\n"
    "  --out FILE          CSV of the probed points\n"
    "  --nominal FILE      nominal mesh (nominal.stl of `truecut part`)\n"
    "  --part FILE         part.json with the surface id of every nominal triangle\n"
    "  --surfaces LIST     surface ids to probe, comma-separated\n"
    "  --spacing MM        distance between probed points (default 1.0)\n"
    "  --max-points N      budget: refuse (exit 2) a --spacing or --points file that\n"
    "                      would probe more points (default 2000000, about 0.5 KB each)\n"
    "  --points FILE       probe these points instead\n"
    "  --sigma-um S        probing noise, 0..20 um (default 2)\n"
    "  --search-mm D       search distance along the normal each way (default 1.0)\n"
    "  --seed N            noise seed (default 1)\n"
    "  --quiet             nothing on stderr but warnings and errors\n"
    "                      (progress is shown on a terminal only)\n"
    "  --help              this text\n";

int input_error(const std::string& message) {
  std::fprintf(stderr, "truecut cmm: %s\n", message.c_str());
  return kExitUsage;
}

}  // namespace

int cmd_cmm(const std::vector<std::string>& argv) {
  std::vector<OptionSpec> specs = cmm_option_specs("");
  specs.insert(specs.end(), {{"out", true},
                             {"nominal", true},
                             {"part", true},
                             {"points", true},
                             kQuietOption,
                             {"help", false}});
  ParsedArgs a(argv, specs);
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
  refuse_output_over_input("out", *out, {mesh_file, points_file, nominal_file, part_file});
  require_replaceable(*out);
  require_writable_file("out", *out);
  const CmmSettings settings = cmm_settings(a, "");
  const sim::measure::CmmOptions& opt = settings.options;

  offline::TriangleMesh machined;
  std::vector<sim::measure::CmmPoint> points;
  try {
    machined = offline::read_mesh(mesh_file);
    if (machined.triangles.empty()) return input_error(mesh_file + ": no triangles");
    if (points_file) {
      points = sim::measure::read_cmm_points(*points_file);
      check_probe_budget(points.size(), *points_file, settings);
    } else {
      points = cmm_points_on_part(*nominal_file, *part_file, settings);
    }
  } catch (const offline::MeshIoError& e) {
    return input_error(e.what());
  } catch (const sim::measure::CmmInputError& e) {
    return input_error(e.what());
  } catch (const sim::measure::PartFileError& e) {
    return input_error(e.what());
  } catch (const MeasureInputError& e) {
    return input_error(e.what());
  }

  if (progress_shown(a))
    std::fprintf(stderr, "cmm: probing %zu points on %s\n", points.size(), mesh_file.c_str());
  std::vector<sim::measure::CmmMeasurement> measurements;
  try {
    measurements = sim::measure::probe(machined, points, opt);
  } catch (const std::invalid_argument& e) {
    return input_error(e.what());
  }
  // No table of zeros, no file.
  if (!some_probe_found_the_surface(
          measurements, "truecut cmm", mesh_file, opt.search_distance_mm, "nothing written",
          "is the mesh in mm and in the workpiece frame? --search-mm widens the search"))
    return kExitFailure;
  const auto overall = sim::measure::overall_statistics(measurements);
  sim::measure::write_cmm_csv(*out, measurements);

  print_cmm_table(measurements);
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
