// truecut scan MESH --out SCAN.ply: the virtual optical scanner.
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "args.hpp"
#include "commands.hpp"
#include "measure_options.hpp"
#include "quiet_option.hpp"
#include "truecut/offline/mesh_io.hpp"
#include "truecut/offline/rigid_transform.hpp"
#include "truecut/sim/measure/scanner.hpp"

namespace truecut::cli {
namespace {

const char* kScanHelp =
    "usage: truecut scan MESH --out SCAN.ply [options]\n"
    "\n"
    "Scans MESH (the machined surface: STL or PLY, workpiece frame, mm) with a\n"
    "virtual optical scanner from five poses around the part (above, +-X, +-Y; none\n"
    "from below) and writes the measured point cloud with normals. Points exist only\n"
    "where the scanner's two devices see the surface at <= 75 deg incidence; each is\n"
    "displaced along its ray by Gaussian noise sigma0/cos(incidence) (capped at 3x).\n"
    "Models: docs/measurement.md.\n"
    "\n"
    "options:\n"
    "  --out FILE                   point cloud: .ply (binary), .xyz, .txt or .csv\n"
    "  --sigma-um S                 noise at normal incidence, 5..50 um (default 20)\n"
    "  --density PT_PER_MM2         points per mm^2 facing the scanner (default 25)\n"
    "  --mode fringe|laser          fringe projection (default) or laser line\n"
    "  --max-incidence-deg DEG      steeper rays give no point (default 75)\n"
    "  --registration-error-mm D    shift the whole cloud by D mm (random direction)\n"
    "  --registration-error-deg R   and turn it by R deg about the part's box centre\n"
    "  --seed N                     noise and registration seed (default 1)\n"
    "  --normals estimate|view      plane fit to neighbours (default) or view direction\n"
    "  --mesh-out FILE              also a triangulated scan mesh (.ply or .stl)\n"
    "  --quiet                      nothing on stderr but warnings and errors\n"
    "                               (progress is shown on a terminal only)\n"
    "  --help                       this text\n";

// Whether two output names reach the same file, which need not exist yet
// (refuse_output_over_input covers existing files): the same folder, by
// identity, and the same name in it.
bool same_new_file(const std::string& a, const std::string& b) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::equivalent(a, b, ec) && !ec) return true;
  const fs::path pa = fs::absolute(a), pb = fs::absolute(b);
  const fs::path da = pa.parent_path(), db = pb.parent_path();
  const bool same_folder = da == db || (fs::equivalent(da, db, ec) && !ec);
  return same_folder && pa.filename() == pb.filename();
}

}  // namespace

int cmd_scan(const std::vector<std::string>& argv) {
  std::vector<OptionSpec> specs = scan_option_specs("");
  specs.insert(specs.end(), {{"out", true}, {"mesh-out", true}, kQuietOption, {"help", false}});
  ParsedArgs a(argv, specs);
  if (a.flag("help")) {
    std::fputs(kScanHelp, stdout);
    return kExitOk;
  }
  if (a.positionals().size() != 1) throw UsageError("expected one MESH file");
  const std::string mesh_file = a.positionals()[0];
  const auto out = a.value("out");
  if (!out) throw UsageError("--out FILE is required");
  if (!has_extension(*out, {".ply", ".xyz", ".txt", ".csv"}))
    throw UsageError("--out " + *out + ": the point cloud must be .ply, .xyz, .txt or .csv");
  const auto mesh_out = a.value("mesh-out");
  if (mesh_out && !has_extension(*mesh_out, {".ply", ".stl"}))
    throw UsageError("--mesh-out " + *mesh_out + ": the scan mesh must be .ply or .stl");

  refuse_output_over_input("out", *out, {mesh_file, mesh_out});
  if (mesh_out) refuse_output_over_input("mesh-out", *mesh_out, {mesh_file});
  if (mesh_out && same_new_file(*out, *mesh_out))
    throw UsageError("--out " + *out + " and --mesh-out " + *mesh_out +
                     " name the same file: the scan mesh would replace the point cloud; choose "
                     "two names");
  require_replaceable(*out);
  if (mesh_out) require_replaceable(*mesh_out);
  require_writable_file("out", *out);
  if (mesh_out) require_writable_file("mesh-out", *mesh_out);
  ScanSettings settings = scan_settings(a, "");
  settings.show_progress = progress_shown(a);
  const sim::measure::ScannerOptions& opt = settings.options;
  settings.options.build_mesh = mesh_out.has_value();

  offline::TriangleMesh mesh;
  try {
    mesh = offline::read_mesh(mesh_file);
  } catch (const offline::MeshIoError& e) {
    std::fprintf(stderr, "truecut scan: %s\n", e.what());
    return kExitUsage;
  }
  if (mesh.triangles.empty()) {
    std::fprintf(stderr, "truecut scan: %s: no triangles (a mesh is needed, not points)\n",
                 mesh_file.c_str());
    return kExitUsage;
  }
  sim::measure::ScanResult result;
  try {
    result = scan_mesh(mesh, settings);
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "truecut scan: %s: %s\n", mesh_file.c_str(), e.what());
    return kExitUsage;
  }
  if (result.cloud.points_mm.empty()) {
    std::fprintf(stderr, "truecut scan: %s: no point measured; nothing written\n",
                 mesh_file.c_str());
    return kExitFailure;
  }
  offline::MeshWriteOptions write;
  write.comment = scan_comment(settings);
  offline::write_point_cloud(*out, result.cloud, write);
  if (mesh_out) offline::write_mesh(*mesh_out, result.mesh, write);

  const auto& s = result.stats;
  std::printf(
      "scan: %zu poses, %zu rays (spacing %.4f mm), %zu hits, %zu beyond %.0f deg, "
      "%zu occluded -> %zu points in %s\n",
      result.poses.size(), s.rays, s.ray_spacing_mm, s.hits, s.rejected_incidence,
      opt.max_incidence_deg, s.occluded, s.points, out->c_str());
  if (mesh_out)
    std::printf("scan mesh: %zu triangles in %s\n", result.mesh.triangles.size(),
                mesh_out->c_str());
  if (opt.registration_error) {
    const auto r = offline::describe_transform(*opt.registration_error);
    std::printf(
        "registration error: translation (%.4f, %.4f, %.4f) mm, rotation %.4f deg about "
        "(%.3f, %.3f, %.3f)\n",
        r.translation_mm.x(), r.translation_mm.y(), r.translation_mm.z(), r.rotation_angle_deg,
        r.rotation_axis.x(), r.rotation_axis.y(), r.rotation_axis.z());
  }
  return kExitOk;
}

namespace {
const CommandRegistration kRegistration{
    "scan", "virtual optical scan of a machined mesh: point cloud", cmd_scan, 30};
}  // namespace

}  // namespace truecut::cli
