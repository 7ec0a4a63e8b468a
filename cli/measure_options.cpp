#include "measure_options.hpp"

#include <stdlib.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "truecut/offline/mesh_io.hpp"
#include "truecut/rt/atomic_write.hpp"
#include "truecut/rt/number_format.hpp"
#include "truecut/sim/measure/part_surfaces.hpp"

namespace truecut::cli {
namespace {

std::vector<std::int32_t> parse_surface_list(const std::string& option, const std::string& text) {
  std::vector<std::int32_t> ids;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = std::min(text.find(',', start), text.size());
    const std::string item = text.substr(start, comma - start);
    char* end = nullptr;
    const long v = std::strtol(item.c_str(), &end, 10);
    if (item.empty() || *end != '\0' || v < -2147483647L || v > 2147483647L)
      throw UsageError("--" + option + " '" + text + "': '" + item + "' is not a surface id");
    ids.push_back(static_cast<std::int32_t>(v));
    start = comma + 1;
  }
  return ids;
}

void print_row(const sim::measure::SurfaceDeviationStats& s, const char* indent) {
  const std::string name = s.surface < 0 ? "all" : std::to_string(s.surface);
  if (s.valid == 0) {
    std::printf("%s%-8s %7zu %7zu %9s %9s %9s %9s %9s\n", indent, name.c_str(), s.points, s.valid,
                "-", "-", "-", "-", "-");
    return;
  }
  std::printf("%s%-8s %7zu %7zu %9.2f %9.2f %9.2f %9.2f %9.2f\n", indent, name.c_str(), s.points,
              s.valid, s.mean_um, s.std_um, s.rms_um, s.max_abs_um, s.p95_abs_um);
}

// The area of the triangles of `surfaces` (empty: all).
double surfaces_area_mm2(const offline::TriangleMesh& mesh, const std::vector<std::int32_t>& ids,
                         const std::vector<std::int32_t>& surfaces) {
  double area = 0.0;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    if (!surfaces.empty() && std::find(surfaces.begin(), surfaces.end(), ids[t]) == surfaces.end())
      continue;
    const auto& [a, b, c] = mesh.triangles[t];
    const Eigen::Vector3d &pa = mesh.vertices_mm[a], &pb = mesh.vertices_mm[b],
                          &pc = mesh.vertices_mm[c];
    area += 0.5 * (pb - pa).cross(pc - pa).norm();
  }
  return area;
}

namespace fs = std::filesystem;

// DIR itself when it exists, else its nearest existing parent.
fs::path nearest_existing(const fs::path& dir) {
  std::error_code ec;
  fs::path p = fs::absolute(dir, ec);
  if (ec) p = dir;
  while (!p.empty() && !fs::exists(p, ec) && p != p.parent_path())
    p = p.parent_path();
  return p;
}

void probe_folder(const std::string& option, const std::string& given, const fs::path& folder) {
  std::error_code ec;
  if (!fs::is_directory(folder, ec))
    throw UsageError("--" + option + " " + given + ": " + folder.string() + " is not a folder");
  std::string name = (folder / ".truecut-write-probe-XXXXXX").string();
  const int fd = ::mkstemp(name.data());
  if (fd < 0)
    throw UsageError("--" + option + " " + given + ": cannot write in " + folder.string() + ": " +
                     std::strerror(errno) + " (checked before any work; nothing written)");
  ::close(fd);
  ::unlink(name.c_str());
}

}  // namespace

void require_writable_folder(const std::string& option, const std::string& dir) {
  if (dir.empty()) throw UsageError("--" + option + ": an empty folder name");
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
    throw UsageError("--" + option + " " + dir + ": exists and is not a folder");
  probe_folder(option, dir, nearest_existing(dir));
}

void require_writable_file(const std::string& option, const std::string& file) {
  if (file.empty()) throw UsageError("--" + option + ": an empty file name");
  const fs::path parent = fs::path(file).parent_path();
  const fs::path folder = parent.empty() ? fs::path(".") : parent;
  std::error_code ec;
  if (!fs::is_directory(folder, ec))
    throw UsageError("--" + option + " " + file + ": the folder " + folder.string() +
                     " does not exist");
  probe_folder(option, file, folder);
}

void require_replaceable(const std::string& file) {
  try {
    rt::require_replaceable(file);
  } catch (const rt::FileWriteError& e) {
    throw UsageError(e.what());
  }
}

bool has_extension(const std::string& file, std::initializer_list<const char*> extensions) {
  const auto format = offline::format_from_extension(file);
  std::string ext = std::filesystem::path(file).extension().string();
  for (auto& ch : ext)
    ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  for (const char* e : extensions)
    if (ext == e) return format.has_value();
  return false;
}

std::vector<OptionSpec> scan_option_specs(const std::string& prefix) {
  std::vector<OptionSpec> specs;
  for (const char* name : {"sigma-um", "density", "mode", "max-incidence-deg",
                           "registration-error-mm", "registration-error-deg", "seed", "normals"})
    specs.push_back({prefix + name, true});
  return specs;
}

ScanSettings scan_settings(const ParsedArgs& a, const std::string& p) {
  ScanSettings s;
  sim::measure::ScannerOptions& opt = s.options;
  opt.sigma0_mm = a.number(p + "sigma-um", 20.0, 5.0, 50.0) / 1000.0;
  s.sigma_text = a.value(p + "sigma-um").value_or("20");
  opt.density_pt_per_mm2 = a.number(p + "density", opt.density_pt_per_mm2, 1e-3, 1e4);
  opt.max_incidence_deg = a.number(p + "max-incidence-deg", opt.max_incidence_deg, 1.0, 89.0);
  opt.seed = static_cast<std::uint64_t>(a.integer(p + "seed", 1, 0, 0x7fffffffffffffffL));
  s.mode = a.value(p + "mode").value_or("fringe");
  if (s.mode == "laser")
    opt.mode = sim::measure::ScanMode::kLaser;
  else if (s.mode != "fringe")
    throw UsageError("--" + p + "mode '" + s.mode + "': expected fringe or laser");
  const std::string normals = a.value(p + "normals").value_or("estimate");
  if (normals != "estimate" && normals != "view")
    throw UsageError("--" + p + "normals '" + normals + "': expected estimate or view");
  opt.estimate_normals = normals == "estimate";
  s.registration_error_mm = a.number(p + "registration-error-mm", 0.0, 0.0, 10.0);
  s.registration_error_deg = a.number(p + "registration-error-deg", 0.0, 0.0, 10.0);
  return s;
}

sim::measure::ScanResult scan_mesh(const offline::TriangleMesh& mesh, ScanSettings& s) {
  if (mesh.vertices_mm.empty()) throw std::invalid_argument("no vertices");
  if (s.registration_error_mm > 0 || s.registration_error_deg > 0) {
    Eigen::Vector3d lo = mesh.vertices_mm.front(), hi = lo;
    for (const Eigen::Vector3d& p : mesh.vertices_mm) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    s.options.registration_error = sim::measure::seeded_registration_error(
        s.registration_error_mm, s.registration_error_deg, 0.5 * (lo + hi), s.options.seed);
  }
  if (s.show_progress)
    s.options.progress = [](std::size_t pose, std::size_t poses, std::size_t points) {
      std::fprintf(stderr, "scan: pose %zu/%zu, %zu points\n", pose + 1, poses, points);
    };
  return sim::measure::scan(mesh, s.options);
}

std::string scan_comment(const ScanSettings& s) {
  return "truecut scan " + s.mode + " sigma0_um=" + s.sigma_text +
         " density_pt_per_mm2=" + std::to_string(s.options.density_pt_per_mm2) +
         " seed=" + std::to_string(s.options.seed) + ", workpiece frame, mm";
}

std::vector<OptionSpec> cmm_option_specs(const std::string& prefix) {
  std::vector<OptionSpec> specs;
  for (const char* name : {"sigma-um", "search-mm", "seed", "spacing", "surfaces", "max-points"})
    specs.push_back({prefix + name, true});
  return specs;
}

CmmSettings cmm_settings(const ParsedArgs& a, const std::string& p) {
  CmmSettings s;
  s.options.sigma_mm = a.number(p + "sigma-um", 2.0, 0.0, 20.0) / 1000.0;
  s.options.search_distance_mm =
      a.number(p + "search-mm", s.options.search_distance_mm, 1e-3, 100.0);
  s.options.seed = static_cast<std::uint64_t>(a.integer(p + "seed", 1, 0, 0x7fffffffffffffffL));
  s.spacing_mm = a.number(p + "spacing", 1.0, 0.01, 1000.0);
  s.max_points = a.number(p + "max-points", s.max_points, 1.0, 1e12);
  s.prefix = p;
  if (const auto list = a.value(p + "surfaces"))
    s.surfaces = parse_surface_list(p + "surfaces", *list);
  return s;
}

std::vector<sim::measure::CmmPoint> cmm_points_on_part(const std::string& nominal_file,
                                                       const std::string& part_file,
                                                       const CmmSettings& settings) {
  const offline::TriangleMesh nominal = offline::read_mesh(nominal_file);
  const sim::measure::PartSurfaces labels = sim::measure::read_part_surfaces(part_file);
  if (labels.triangle_surface_ids.size() != nominal.triangles.size())
    throw MeasureInputError(part_file + ": key 'triangle_surface_ids' has " +
                            std::to_string(labels.triangle_surface_ids.size()) + " entries but " +
                            nominal_file + " has " + std::to_string(nominal.triangles.size()) +
                            " triangles");
  for (std::int32_t id : settings.surfaces)
    if (!labels.has(id))
      throw MeasureInputError(part_file + ": key 'surfaces' has no surface " + std::to_string(id));
  const std::vector<std::int32_t> surfaces =
      settings.surfaces.empty() ? labels.compensated_ids() : settings.surfaces;
  const double area_mm2 = surfaces_area_mm2(nominal, labels.triangle_surface_ids, surfaces);
  const double estimate = area_mm2 / (settings.spacing_mm * settings.spacing_mm);
  if (estimate > settings.max_points)
    throw MeasureInputError(rt::format_printf(
        "--%sspacing %g mm would probe about %.3g points on the %.4g mm² of the selected "
        "surfaces of %s, more than --%smax-points %.0f (about 0.5 KB each); choose a larger "
        "--%sspacing or fewer --%ssurfaces, or raise --%smax-points (a nominal in µm instead "
        "of mm is 1000 times too large)",
        settings.prefix.c_str(), settings.spacing_mm, estimate, area_mm2, nominal_file.c_str(),
        settings.prefix.c_str(), settings.max_points, settings.prefix.c_str(),
        settings.prefix.c_str(), settings.prefix.c_str()));
  auto points = sim::measure::cmm_points_on_surfaces(nominal, labels.triangle_surface_ids,
                                                     settings.spacing_mm, surfaces);
  if (points.empty())
    throw MeasureInputError(nominal_file + ": no points on the selected surfaces");
  return points;
}

void check_probe_budget(std::size_t points, const std::string& source,
                        const CmmSettings& settings) {
  if (double(points) <= settings.max_points) return;
  throw MeasureInputError(rt::format_printf(
      "%s: %zu points to probe, more than --%smax-points %.0f (about 0.5 KB each); raise "
      "--%smax-points",
      source.c_str(), points, settings.prefix.c_str(), settings.max_points,
      settings.prefix.c_str()));
}

void print_cmm_table(const std::vector<sim::measure::CmmMeasurement>& measurements,
                     const char* indent) {
  std::printf("%s%-8s %7s %7s %9s %9s %9s %9s %9s\n", indent, "surface", "points", "valid",
              "mean_um", "std_um", "rms_um", "max_um", "p95_um");
  for (const auto& s : sim::measure::surface_statistics(measurements))
    print_row(s, indent);
  print_row(sim::measure::overall_statistics(measurements), indent);
}

bool some_probe_found_the_surface(const std::vector<sim::measure::CmmMeasurement>& measurements,
                                  const std::string& command, const std::string& mesh_file,
                                  double search_mm, const std::string& not_written,
                                  const std::string& hint) {
  const auto overall = sim::measure::overall_statistics(measurements);
  if (overall.valid > 0) return true;
  std::fprintf(stderr,
               "%s: none of the %zu points found the surface of %s within %g mm along its "
               "normal: no measurement, %s (%s)\n",
               command.c_str(), overall.points, mesh_file.c_str(), search_mm, not_written.c_str(),
               hint.c_str());
  return false;
}

}  // namespace truecut::cli
