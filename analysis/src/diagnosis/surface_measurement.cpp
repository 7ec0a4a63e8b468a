// Measurements for surface mode: CMM CSVs with deviations, and scans
// registered to the nominal and evaluated at nominal points.
#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <unordered_map>

#include "truecut/analysis/diagnosis/surface.hpp"
#include "truecut/offline/mesh_io.hpp"
#include "truecut/offline/ray_scene.hpp"
#include "truecut/offline/registration.hpp"
#include "truecut/rt/input_file.hpp"
#include "truecut/rt/number_format.hpp"

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

// A surface id: a whole number from -1 (none) to the largest int.
int surface_id(double v, const std::string& where) {
  if (!(v == std::floor(v) && v >= -1 && v <= double(std::numeric_limits<int>::max())))
    throw DiagnosisError(where + ": surface '" + rt::format_shortest(v) +
                         "' is not a surface id (a whole number from -1, none, to " +
                         std::to_string(std::numeric_limits<int>::max()) + ")");
  return static_cast<int>(v);
}

// A CMM searches at most this far along the normal (`truecut cmm --search-mm`
// up to 100): a larger deviation is a unit mix-up or a corrupt row, and its
// square overflows the fits downstream (1e300 gave "rms inf").
constexpr double kMaxDeviationMm = 100.0;

void check_deviation(double deviation_mm, const std::string& where) {
  if (std::isnan(deviation_mm) || std::abs(deviation_mm) <= kMaxDeviationMm) return;
  throw DiagnosisError(where + ": deviation_mm " + rt::format_shortest(deviation_mm) +
                       " is outside ±" + rt::format_shortest(kMaxDeviationMm) +
                       " mm (a CMM searches at most 100 mm along the normal; check the unit)");
}

// The cloud points near each nominal point are found through a grid of
// cells of the search radius.
struct CloudGrid {
  double cell = 1.0;
  std::unordered_map<long long, std::vector<std::size_t>> cells;
  static long long key(long long i, long long j, long long k) {
    return (i * 73856093LL) ^ (j * 19349663LL) ^ (k * 83492791LL);
  }
  static std::array<long long, 3> index(const Eigen::Vector3d& p, double cell) {
    const Eigen::Vector3d c = p / cell;
    return {std::llround(std::floor(c.x())), std::llround(std::floor(c.y())),
            std::llround(std::floor(c.z()))};
  }
  CloudGrid(const std::vector<Eigen::Vector3d>& points, double cell_mm) : cell(cell_mm) {
    for (std::size_t i = 0; i < points.size(); ++i) {
      const auto [a, b, c] = index(points[i], cell);
      cells[key(a, b, c)].push_back(i);
    }
  }
};

// The nominal surface a cloud point lies on: that of its closest nominal
// triangle within `reach_mm`, -2 when none is so close. Found when first
// asked (most cloud points are never near a nominal point of the sampling).
class CloudSurfaces {
 public:
  static constexpr int kNone = -2;
  CloudSurfaces(const offline::TriangleMesh& nominal, const std::vector<std::int32_t>& ids,
                const std::vector<Eigen::Vector3d>& cloud, double reach_mm)
      : scene_(nominal),
        ids_(ids),
        cloud_(cloud),
        reach_mm_(reach_mm),
        surface_(cloud.size(), kUnknown) {}

  int of(std::size_t i) {
    if (surface_[i] != kUnknown) return surface_[i];
    near_.clear();
    scene_.triangles_within(cloud_[i], reach_mm_, near_);
    double best = std::numeric_limits<double>::infinity();
    int surface = kNone;
    for (const auto& t : near_) {
      const double d = (t.closest_mm - cloud_[i]).squaredNorm();
      if (d < best && t.triangle < ids_.size()) best = d, surface = ids_[t.triangle];
    }
    return surface_[i] = surface;
  }

 private:
  static constexpr int kUnknown = -3;
  offline::RayScene scene_;
  const std::vector<std::int32_t>& ids_;
  const std::vector<Eigen::Vector3d>& cloud_;
  double reach_mm_;
  std::vector<int> surface_;
  std::vector<offline::RayScene::NearTriangle> near_;
};

// A cloud point's normal may differ from the nominal's by at most this
// (the CMM's own limit, CmmOptions::max_normal_angle_deg): beyond, it sees
// another face.
constexpr double kCloudNormalCos = 0.5;

// The deviation of a registered point cloud at nominal points: the mean
// offset along the normal of the cloud points within `radius_mm` of the
// normal line and `depth_mm` along it that lie on the nominal point's own
// surface (closest nominal triangle) and, when the cloud has normals, face
// the same way. A point with fewer than three such cloud points is not
// measured: at a 1.6 mm shaft's edges the neighbouring faces' points were
// averaged in, and a face the scanner never saw (the part's bottom) got the
// walls' points beside it (issue 23, sweep F2).
std::vector<sim::measure::CmmMeasurement> cloud_deviations(
    const std::vector<sim::measure::CmmPoint>& points, const offline::TriangleMesh& nominal,
    const std::vector<std::int32_t>& triangle_surface, const std::vector<Eigen::Vector3d>& cloud,
    const std::vector<Eigen::Vector3d>& cloud_normals, double radius_mm) {
  constexpr double depth_mm = 1.0;
  const bool normals = cloud_normals.size() == cloud.size();
  const CloudGrid grid(cloud, radius_mm);
  CloudSurfaces surfaces(nominal, triangle_surface, cloud, depth_mm + radius_mm);
  const long long reach = std::llround(std::ceil(depth_mm / grid.cell));
  std::vector<sim::measure::CmmMeasurement> out;
  out.reserve(points.size());
  for (const auto& p : points) {
    sim::measure::CmmMeasurement m;
    m.nominal = p;
    m.deviation_mm = std::numeric_limits<double>::quiet_NaN();
    m.measured_mm.setConstant(std::numeric_limits<double>::quiet_NaN());
    const auto [ci, cj, ck] = CloudGrid::index(p.position_mm, grid.cell);
    double sum = 0;
    int count = 0;
    for (long long di = -reach; di <= reach; ++di)
      for (long long dj = -reach; dj <= reach; ++dj)
        for (long long dk = -reach; dk <= reach; ++dk) {
          const auto it = grid.cells.find(CloudGrid::key(ci + di, cj + dj, ck + dk));
          if (it == grid.cells.end()) continue;
          for (std::size_t idx : it->second) {
            const Eigen::Vector3d d = cloud[idx] - p.position_mm;
            const double along = d.dot(p.normal);
            if (std::abs(along) > depth_mm || (d - along * p.normal).norm() > radius_mm) continue;
            if (normals && cloud_normals[idx].dot(p.normal) < kCloudNormalCos) continue;
            if (surfaces.of(idx) != p.surface) continue;
            sum += along;
            ++count;
          }
        }
    if (count >= 3) {
      m.valid = true;
      m.deviation_mm = sum / count;
      m.measured_mm = p.position_mm + m.deviation_mm * p.normal;
    }
    out.push_back(m);
  }
  return out;
}

}  // namespace

SurfaceMeasurement read_cmm_measurement(const std::filesystem::path& file) {
  try {
    rt::check_input_file(file, "CMM file");
  } catch (const rt::InputFileError& e) {
    throw DiagnosisError(e.what());
  }
  std::ifstream in(file, std::ios::binary);
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
    if (const std::string bad = sim::measure::cmm_coordinate_error(p.nominal.position_mm);
        !bad.empty())
      throw DiagnosisError(where + ": " + bad);
    p.nominal.normal = n.normalized();
    p.nominal.surface = col.count("surface") ? surface_id(get("surface"), where) : -1;
    p.deviation_mm = get("deviation_mm");
    check_deviation(p.deviation_mm, where);
    const double valid = col.count("valid") ? get("valid") : 1.0;
    if (valid != 0 && valid != 1)
      throw DiagnosisError(where + ": valid '" + rt::format_shortest(valid) + "' is not 0 or 1");
    p.valid = std::isfinite(p.deviation_mm) && valid == 1;
    p.measured_mm = p.nominal.position_mm + p.deviation_mm * p.nominal.normal;
    m.points.push_back(p);
  }
  if (in.bad()) throw DiagnosisError(file.string() + ": read error");
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
  } catch (const offline::MeshIoError& e) {
    throw DiagnosisError(e.what());  // names the file
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
  // A cloud: its normals turned with the registration.
  for (auto& n : scan.normals)
    n = (icp.scan_to_nominal.linear() * n).normalized();
  m.points = cloud_deviations(points, nominal, triangle_surface, scan.vertices_mm, scan.normals,
                              std::max(spacing_mm, 0.2));
  return m;
}

}  // namespace truecut::analysis::diagnosis
