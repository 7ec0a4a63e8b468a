// CMM probing: from the nominal point, a ray along +normal and one along
// −normal to the machined mesh; of the hits whose surface faces the same way
// as the nominal one, the nearer gives the deviation; probing noise is added
// along the normal.
#include "truecut/sim/measure/cmm.hpp"

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

#include "counter_rng.hpp"
#include "truecut/offline/compensation_points.hpp"
#include "truecut/offline/ray_scene.hpp"

namespace truecut::sim::measure {
namespace {

void validate(const CmmOptions& o) {
  if (!(o.sigma_mm >= 0 && o.sigma_mm <= 0.020))
    throw std::invalid_argument("CMM sigma " + std::to_string(o.sigma_mm * 1000) +
                                " µm is outside 0–20 µm");
  if (!(o.search_distance_mm > 0 && std::isfinite(o.search_distance_mm)))
    throw std::invalid_argument("CMM search distance must be positive");
  if (!(o.max_normal_angle_deg > 0 && o.max_normal_angle_deg < 90))
    throw std::invalid_argument("CMM max_normal_angle_deg must be in (0, 90)");
}

}  // namespace

std::vector<CmmMeasurement> probe(const offline::TriangleMesh& machined,
                                  std::span<const CmmPoint> points, const CmmOptions& options) {
  validate(options);
  if (machined.triangles.empty()) throw std::invalid_argument("CMM: the machined mesh is empty");
  std::vector<CmmMeasurement> out(points.size());
  std::vector<offline::Ray> rays(2 * points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const CmmPoint& p = points[i];
    const double length = p.normal.norm();
    if (!p.position_mm.allFinite() || !p.normal.allFinite() || !(length > 1e-12))
      throw std::invalid_argument("CMM point " + std::to_string(i + 1) +
                                  ": non-finite coordinate or zero normal");
    if (const std::string bad = cmm_coordinate_error(p.position_mm); !bad.empty())
      throw std::invalid_argument("CMM point " + std::to_string(i + 1) + ": " + bad);
    out[i].nominal = p;
    out[i].nominal.normal = p.normal / length;
    for (int side = 0; side < 2; ++side) {
      offline::Ray& r = rays[2 * i + static_cast<std::size_t>(side)];
      r.origin_mm = p.position_mm;
      r.direction = side == 0 ? out[i].nominal.normal : Eigen::Vector3d(-out[i].nominal.normal);
      r.t_min_mm = 0;
      r.t_max_mm = options.search_distance_mm;
    }
  }
  std::vector<offline::RayHit> hits(rays.size());
  if (!rays.empty()) offline::RayScene(machined).intersect(rays, hits);

  const double cos_max = std::cos(options.max_normal_angle_deg * std::numbers::pi / 180.0);
  for (std::size_t i = 0; i < points.size(); ++i) {
    CmmMeasurement& m = out[i];
    const Eigen::Vector3d& n = m.nominal.normal;
    double best = std::numeric_limits<double>::infinity();
    for (int side = 0; side < 2; ++side) {
      const offline::RayHit& h = hits[2 * i + static_cast<std::size_t>(side)];
      if (!h.hit() || h.normal.dot(n) < cos_max) continue;
      const double signed_mm = side == 0 ? h.distance_mm : -h.distance_mm;
      if (std::abs(signed_mm) < std::abs(best)) best = signed_mm;
    }
    m.valid = std::isfinite(best);
    if (!m.valid) {
      m.deviation_mm = std::numeric_limits<double>::quiet_NaN();
      m.measured_mm.setConstant(std::numeric_limits<double>::quiet_NaN());
      continue;
    }
    m.deviation_mm = best + options.sigma_mm * standard_normal(options.seed, 0, i);
    m.measured_mm = m.nominal.position_mm + m.deviation_mm * n;
  }
  return out;
}

std::vector<CmmPoint> cmm_points_on_surfaces(const offline::TriangleMesh& nominal,
                                             std::span<const std::int32_t> triangle_surface_ids,
                                             double spacing_mm,
                                             std::span<const std::int32_t> surfaces) {
  const offline::CompensationPoints sampled =
      offline::sample_compensation_points(nominal, triangle_surface_ids, spacing_mm, surfaces);
  std::vector<CmmPoint> out(sampled.size());
  for (std::size_t i = 0; i < sampled.size(); ++i)
    out[i] = {sampled.positions_mm[i], sampled.normals[i], sampled.surface_ids[i]};
  return out;
}

}  // namespace truecut::sim::measure
