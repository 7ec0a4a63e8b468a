// Measurements for surface mode: CMM CSVs with deviations, and scans
// registered to the nominal and evaluated at nominal points.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <unordered_map>

#include "truecut/analysis/diagnosis/surface.hpp"
#include "truecut/offline/mesh_io.hpp"
#include "truecut/offline/registration.hpp"

namespace truecut::analysis::diagnosis {

namespace {

std::vector<std::string> split_fields(const std::string& line) {
  std::vector<std::string> out;
  std::string cur;
  for (char ch : line) {
    if (ch == ',' || ch == ';' || ch == ' ' || ch == '\t' || ch == '\r') {
      if (!cur.empty()) out.push_back(cur), cur.clear();
    } else {
      cur += ch;
    }
  }
  if (!cur.empty()) out.push_back(cur);
  return out;
}

double parse_number(const std::string& s, const std::string& where) {
  if (s == "nan" || s == "NaN") return std::numeric_limits<double>::quiet_NaN();
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(s, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != s.size()) throw DiagnosisError(where + ": '" + s + "' is not a number");
  return v;
}

// Deviation of a point cloud at a nominal point: the mean offset along the
// normal of the cloud points within `radius` of the normal line, near the
// nominal point (a local plane, read along the normal).
struct CloudGrid {
  double cell = 1.0;
  std::unordered_map<long long, std::vector<std::size_t>> cells;
  static long long key(long long i, long long j, long long k) {
    return (i * 73856093LL) ^ (j * 19349663LL) ^ (k * 83492791LL);
  }
};

}  // namespace

SurfaceMeasurement read_cmm_measurement(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw DiagnosisError(file.string() + ": cannot read");
  SurfaceMeasurement m;
  m.source = file.string();
  m.kind = "cmm";
  std::string line;
  std::map<std::string, std::size_t> col;
  std::size_t line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (const auto h = line.find('#'); h != std::string::npos) line.resize(h);
    const auto f = split_fields(line);
    if (f.empty()) continue;
    const std::string where = file.string() + ":" + std::to_string(line_no);
    if (col.empty()) {
      for (std::size_t i = 0; i < f.size(); ++i)
        col[f[i]] = i;
      for (const char* need : {"x", "y", "z", "nx", "ny", "nz", "deviation_mm"})
        if (!col.count(need))
          throw DiagnosisError(where + ": the header has no column '" + need +
                               "' (x,y,z,nx,ny,nz,surface,deviation_mm,valid)");
      continue;
    }
    auto get = [&](const char* name) {
      const std::size_t i = col.at(name);
      if (i >= f.size()) throw DiagnosisError(where + ": no value for '" + name + "'");
      return parse_number(f[i], where);
    };
    sim::measure::CmmMeasurement p;
    p.nominal.position_mm = {get("x"), get("y"), get("z")};
    Eigen::Vector3d n(get("nx"), get("ny"), get("nz"));
    if (!p.nominal.position_mm.allFinite() || !n.allFinite() || n.norm() == 0)
      throw DiagnosisError(where + ": a non-finite coordinate or a zero normal");
    p.nominal.normal = n.normalized();
    p.nominal.surface = col.count("surface") ? int(get("surface")) : -1;
    p.deviation_mm = get("deviation_mm");
    p.valid = std::isfinite(p.deviation_mm) && (!col.count("valid") || get("valid") != 0);
    p.measured_mm = p.nominal.position_mm + p.deviation_mm * p.nominal.normal;
    m.points.push_back(p);
  }
  if (m.points.empty()) throw DiagnosisError(file.string() + ": no points");
  return m;
}

SurfaceMeasurement read_scan_measurement(const std::filesystem::path& file,
                                         const offline::TriangleMesh& nominal,
                                         const std::vector<std::int32_t>& triangle_surface,
                                         double spacing_mm) {
  SurfaceMeasurement m;
  m.source = file.string();
  m.kind = "scan";
  offline::TriangleMesh scan;
  try {
    scan = offline::read_mesh(file);
  } catch (const std::exception& e) {
    throw DiagnosisError(file.string() + ": " + e.what());
  }
  if (scan.vertices_mm.empty()) throw DiagnosisError(file.string() + ": no points");
  const auto icp = offline::register_scan(nominal, scan.vertices_mm);
  m.scan_to_nominal = icp.scan_to_nominal;
  m.icp_rms_before_mm = icp.rms_before_mm;
  m.icp_rms_after_mm = icp.rms_after_mm;
  for (auto& v : scan.vertices_mm)
    v = icp.scan_to_nominal * v;
  const auto points = sim::measure::cmm_points_on_surfaces(nominal, triangle_surface, spacing_mm);
  if (!scan.triangles.empty()) {
    sim::measure::CmmOptions o;
    o.sigma_mm = 0.0;
    m.points = sim::measure::probe(scan, points, o);
    return m;
  }
  // A cloud: points within `r` of the normal line through the nominal point
  // and within `depth` along it; their mean offset along the normal.
  const double r = std::max(spacing_mm, 0.2), depth = 1.0;
  CloudGrid grid;
  grid.cell = r;
  for (std::size_t i = 0; i < scan.vertices_mm.size(); ++i) {
    const Eigen::Vector3d c = scan.vertices_mm[i] / grid.cell;
    grid.cells[CloudGrid::key(std::llround(std::floor(c.x())), std::llround(std::floor(c.y())),
                              std::llround(std::floor(c.z())))]
        .push_back(i);
  }
  const int reach = int(std::ceil(depth / grid.cell));
  for (const auto& p : points) {
    sim::measure::CmmMeasurement out;
    out.nominal = p;
    out.deviation_mm = std::numeric_limits<double>::quiet_NaN();
    const Eigen::Vector3d c = p.position_mm / grid.cell;
    const long long ci = std::llround(std::floor(c.x())), cj = std::llround(std::floor(c.y())),
                    ck = std::llround(std::floor(c.z()));
    double sum = 0;
    int count = 0;
    for (int di = -reach; di <= reach; ++di)
      for (int dj = -reach; dj <= reach; ++dj)
        for (int dk = -reach; dk <= reach; ++dk) {
          const auto it = grid.cells.find(CloudGrid::key(ci + di, cj + dj, ck + dk));
          if (it == grid.cells.end()) continue;
          for (std::size_t idx : it->second) {
            const Eigen::Vector3d d = scan.vertices_mm[idx] - p.position_mm;
            const double along = d.dot(p.normal);
            if (std::abs(along) > depth || (d - along * p.normal).norm() > r) continue;
            sum += along;
            ++count;
          }
        }
    if (count >= 3) {
      out.valid = true;
      out.deviation_mm = sum / count;
      out.measured_mm = p.position_mm + out.deviation_mm * p.normal;
    }
    m.points.push_back(out);
  }
  return m;
}

}  // namespace truecut::analysis::diagnosis
