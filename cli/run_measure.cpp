#include "run_measure.hpp"

#include "quiet_option.hpp"

#include <cstdio>

#include "truecut/offline/mesh_io.hpp"
#include "truecut/sim/part_file.hpp"
#include "truecut/sim/soft_cnc_outputs.hpp"

namespace truecut::cli {
namespace {

namespace fs = std::filesystem;

// NAME inside the run's folder: no absolute path, no '..' (the run writes
// only into --out, as the recorder's file= does).
void require_inside_out_dir(const std::string& option, const std::string& given) {
  const fs::path named(given);
  bool outside = named.is_absolute();
  for (const auto& part : named)
    outside = outside || part == "..";
  if (outside)
    throw UsageError("--" + option + " " + given +
                     ": outside the output folder; the run writes a name inside --out (no "
                     "absolute path, no '..')");
}

fs::path output_file(const std::string& option, const std::string& given, const fs::path& out_dir,
                     const std::vector<fs::path>& inputs) {
  require_inside_out_dir(option, given);
  const fs::path file = out_dir / given;
  for (const char* name : sim::kSoftCncOutputs)
    if (fs::absolute(file).lexically_normal() == fs::absolute(out_dir / name).lexically_normal())
      throw UsageError("--" + option + " " + given + ": the run writes " + name + " itself");
  for (const fs::path& input : inputs) {
    std::error_code ec;
    if (fs::equivalent(file, input, ec) && !ec)
      throw UsageError("--" + option + " " + given + " is the input " + input.string() +
                       ": writing it would replace what is being read; choose another file");
  }
  require_replaceable(file.string());
  return file;
}

// A --PREFIX* option without the option it belongs to.
void refuse_orphans(const ParsedArgs& a, const std::vector<OptionSpec>& specs,
                    const std::string& owner) {
  if (a.value(owner)) return;
  for (const OptionSpec& s : specs)
    if (a.value(s.name)) throw UsageError("--" + s.name + " needs --" + owner);
}

}  // namespace

std::vector<OptionSpec> run_measure_option_specs() {
  std::vector<OptionSpec> specs = scan_option_specs("scan-");
  const std::vector<OptionSpec> cmm = cmm_option_specs("cmm-");
  specs.insert(specs.end(), cmm.begin(), cmm.end());
  specs.push_back({"scan", true});
  specs.push_back({"cmm", true});
  return specs;
}

RunMeasurement prepare_run_measurement(const ParsedArgs& a, const fs::path& out_dir,
                                       const fs::path& nominal, const fs::path& part,
                                       const std::vector<fs::path>& inputs) {
  refuse_orphans(a, scan_option_specs("scan-"), "scan");
  refuse_orphans(a, cmm_option_specs("cmm-"), "cmm");
  RunMeasurement m;
  m.show_progress = progress_shown(a);
  if (const auto scan = a.value("scan")) {
    if (!has_extension(*scan, {".ply", ".xyz", ".txt", ".csv"}))
      throw UsageError("--scan " + *scan + ": the point cloud must be .ply, .xyz, .txt or .csv");
    m.scan_file = output_file("scan", *scan, out_dir, inputs);
    m.scan = scan_settings(a, "scan-");
    m.scan.show_progress = m.show_progress;
  }
  if (const auto cmm = a.value("cmm")) {
    m.cmm_file = output_file("cmm", *cmm, out_dir, inputs);
    if (m.scan_file && fs::absolute(*m.scan_file).lexically_normal() ==
                           fs::absolute(*m.cmm_file).lexically_normal())
      throw UsageError("--scan and --cmm name the same file");
    m.cmm = cmm_settings(a, "cmm-");
    try {
      m.cmm_points = cmm_points_on_part(nominal.string(), part.string(), m.cmm);
    } catch (const offline::MeshIoError& e) {
      throw UsageError(e.what());
    } catch (const sim::PartFileError& e) {
      throw UsageError(e.what());
    } catch (const MeasureInputError& e) {
      throw UsageError(e.what());
    }
  }
  return m;
}

bool measure_machined_part(RunMeasurement& m, const fs::path& machined_stl) {
  if (!m.scan_file && !m.cmm_file) return true;
  const offline::TriangleMesh machined = offline::read_mesh(machined_stl);
  if (m.scan_file) {
    const sim::measure::ScanResult result = scan_mesh(machined, m.scan);
    if (result.cloud.points_mm.empty()) {
      std::fprintf(stderr, "truecut run: %s: the scanner measured no point; %s not written\n",
                   machined_stl.string().c_str(), m.scan_file->string().c_str());
      return false;
    }
    fs::create_directories(m.scan_file->parent_path());
    offline::MeshWriteOptions write;
    write.comment = scan_comment(m.scan);
    offline::write_point_cloud(*m.scan_file, result.cloud, write);
    std::printf("  scan        %zu points (sigma %s um, seed %llu) -> %s\n",
                result.cloud.points_mm.size(), m.scan.sigma_text.c_str(),
                static_cast<unsigned long long>(m.scan.options.seed),
                m.scan_file->string().c_str());
  }
  if (m.cmm_file) {
    if (m.show_progress)
      std::fprintf(stderr, "cmm: probing %zu points on %s\n", m.cmm_points.size(),
                   machined_stl.string().c_str());
    const auto measurements = sim::measure::probe(machined, m.cmm_points, m.cmm.options);
    if (!some_probe_found_the_surface(
            measurements, "truecut run", machined_stl.string(), m.cmm.options.search_distance_mm,
            m.cmm_file->string() + " not written", "--cmm-search-mm widens the search"))
      return false;
    fs::create_directories(m.cmm_file->parent_path());
    sim::measure::write_cmm_csv(*m.cmm_file, measurements);
    std::printf("  cmm         %zu points -> %s (deviations in um)\n", measurements.size(),
                m.cmm_file->string().c_str());
    print_cmm_table(measurements, "    ");
  }
  return true;
}

}  // namespace truecut::cli
