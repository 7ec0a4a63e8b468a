// The scanner's measurement model (docs/measurement.md, "Optical scanner"):
// cast the pose's ray grid, keep hits both devices see within the incidence
// limit, displace each along its ray by Gaussian noise σ0·min(1/cos θ, cap),
// then normals, scan mesh and registration error.
#include "truecut/sim/measure/scanner.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "counter_rng.hpp"
#include "scan_grid.hpp"
#include "scan_surface.hpp"
#include "truecut/offline/ray_scene.hpp"

namespace truecut::sim::measure {
namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;
constexpr std::uint64_t kRegistrationStream = 0;  // pose k draws from stream k + 1
constexpr std::size_t kRaysPerBatch = std::size_t{1} << 20;

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument(what);
}

struct BoundingBox {
  Eigen::Vector3d min_mm, max_mm;
};

BoundingBox bounding_box(const offline::TriangleMesh& mesh) {
  require(!mesh.vertices_mm.empty() && !mesh.triangles.empty(), "scan: the mesh has no triangles");
  BoundingBox box{mesh.vertices_mm.front(), mesh.vertices_mm.front()};
  for (const Eigen::Vector3d& p : mesh.vertices_mm) {
    box.min_mm = box.min_mm.cwiseMin(p);
    box.max_mm = box.max_mm.cwiseMax(p);
  }
  return box;
}

}  // namespace

void validate(const ScannerOptions& o) {
  require(o.sigma0_mm >= 0.005 && o.sigma0_mm <= 0.050, "scanner sigma0 " +
                                                            std::to_string(o.sigma0_mm * 1000) +
                                                            " µm is outside the allowed 5–50 µm");
  require(o.max_incidence_deg > 0 && o.max_incidence_deg < 90,
          "scanner max_incidence_deg must be in (0, 90)");
  require(o.max_sigma_factor >= 1 && std::isfinite(o.max_sigma_factor),
          "scanner max_sigma_factor must be ≥ 1");
  require(o.density_pt_per_mm2 > 0 && o.density_pt_per_mm2 <= 1e4,
          "scanner density must be in (0, 10000] pt/mm²");
  require(o.triangulation_angle_deg > 0 && o.triangulation_angle_deg < 80,
          "scanner triangulation_angle_deg must be in (0, 80)");
  require(o.mesh_edge_factor >= 1 && std::isfinite(o.mesh_edge_factor),
          "scanner mesh_edge_factor must be ≥ 1");
  for (std::size_t i = 0; i < o.poses.size(); ++i) {
    const ScanPose& p = o.poses[i];
    const std::string where = "scan pose " + std::to_string(i + 1);
    require(p.position_mm.allFinite() && p.view_dir.allFinite() && p.up.allFinite(),
            where + ": non-finite position or direction");
    require(p.view_dir.norm() > 1e-9, where + ": zero view direction");
    require(p.up.cross(p.view_dir.normalized()).norm() > 1e-6,
            where + ": up is parallel to the view direction");
    require(p.reference_distance_mm > 0 && std::isfinite(p.reference_distance_mm),
            where + ": reference distance must be positive");
  }
  if (o.registration_error)
    require(o.registration_error->matrix().allFinite(), "registration error is not finite");
}

std::vector<ScanPose> default_scan_poses(const offline::TriangleMesh& mesh) {
  const BoundingBox box = bounding_box(mesh);
  const Eigen::Vector3d centre = 0.5 * (box.min_mm + box.max_mm);
  const double reference = std::max(300.0, 3.0 * (box.max_mm - box.min_mm).norm());
  std::vector<ScanPose> poses;
  auto add = [&](const Eigen::Vector3d& view, const Eigen::Vector3d& up) {
    poses.push_back({centre - reference * view, view, up, reference});
  };
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX(), y = Eigen::Vector3d::UnitY(),
                        z = Eigen::Vector3d::UnitZ();
  add(-z, y);
  add(-x, z);
  add(x, z);
  add(-y, z);
  add(y, z);
  return poses;
}

Eigen::Isometry3d seeded_registration_error(double translation_mm, double rotation_deg,
                                            const Eigen::Vector3d& centre_mm, std::uint64_t seed) {
  require(translation_mm >= 0 && translation_mm <= 10,
          "registration error translation must be in [0, 10] mm");
  require(rotation_deg >= 0 && rotation_deg <= 10,
          "registration error rotation must be in [0, 10] degrees");
  // Two directions uniform on the sphere from normal deviates (rejecting a
  // near-zero vector keeps the draw well defined).
  auto direction = [&](std::uint64_t first) {
    for (std::uint64_t k = first;; k += 3) {
      const Eigen::Vector3d v(standard_normal(seed, kRegistrationStream, k),
                              standard_normal(seed, kRegistrationStream, k + 1),
                              standard_normal(seed, kRegistrationStream, k + 2));
      if (v.norm() > 1e-6) return Eigen::Vector3d(v.normalized());
    }
  };
  const Eigen::Vector3d t_dir = direction(0);
  const Eigen::Vector3d axis = direction(1000);
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();
  transform.translate(centre_mm + translation_mm * t_dir);
  transform.rotate(Eigen::AngleAxisd(rotation_deg * kDegToRad, axis));
  transform.translate(-centre_mm);
  return transform;
}

ScanResult scan(const offline::TriangleMesh& mesh, const ScannerOptions& options) {
  validate(options);
  const BoundingBox box = bounding_box(mesh);  // refuses an empty mesh
  ScanResult result;
  result.poses = options.poses.empty() ? default_scan_poses(mesh) : options.poses;
  const double spacing_mm = 1.0 / std::sqrt(options.density_pt_per_mm2);
  result.stats.ray_spacing_mm = spacing_mm;
  const double cos_max = std::cos(options.max_incidence_deg * kDegToRad);
  const offline::RayScene scene(mesh);
  // Shadow rays start this far from the surface so they do not meet it again.
  const double shadow_offset_mm = std::max(1e-4, 1e-6 * (box.max_mm - box.min_mm).norm());

  std::vector<Eigen::Vector3d>& points = result.cloud.points_mm;
  std::vector<detail::MeasuredGrid> grids;
  std::vector<detail::PoseGrid> pose_grids;
  pose_grids.reserve(result.poses.size());  // the edge limits below refer to its elements
  std::vector<offline::Ray> rays, shadows;
  std::vector<offline::RayHit> hits, shadow_hits;
  struct Candidate {
    std::size_t cell;
    Eigen::Vector3d point_mm;
    double cos_incidence;
  };
  std::vector<Candidate> candidates;

  for (std::size_t pose = 0; pose < result.poses.size(); ++pose) {
    pose_grids.emplace_back(result.poses[pose], pose, options.mode, spacing_mm,
                            options.triangulation_angle_deg, mesh, options.max_rays_per_pose);
    const detail::PoseGrid& grid = pose_grids.back();
    detail::MeasuredGrid measured;
    measured.rows = grid.rows();
    measured.cols = grid.cols();
    measured.point.assign(grid.size(), -1);
    const std::size_t rows_per_batch = std::max<std::size_t>(1, kRaysPerBatch / grid.cols());
    for (std::size_t row0 = 0; row0 < grid.rows(); row0 += rows_per_batch) {
      const std::size_t row1 = std::min(grid.rows(), row0 + rows_per_batch);
      const std::size_t first_cell = row0 * grid.cols();
      rays.clear();
      for (std::size_t r = row0; r < row1; ++r)
        for (std::size_t c = 0; c < grid.cols(); ++c)
          rays.push_back(grid.ray(r, c));
      hits.resize(rays.size());
      scene.intersect(rays, hits);
      result.stats.rays += rays.size();

      candidates.clear();
      shadows.clear();
      for (std::size_t k = 0; k < rays.size(); ++k) {
        if (!hits[k].hit()) continue;
        ++result.stats.hits;
        const offline::Ray& ray = rays[k];
        const Eigen::Vector3d& n = hits[k].normal;
        const double cos_in = -ray.direction.dot(n);
        const Eigen::Vector3d x = ray.origin_mm + hits[k].distance_mm * ray.direction;
        const std::size_t cell = first_cell + k;
        const Eigen::Vector3d to_partner = grid.partner_mm(cell / grid.cols()) - x;
        const double partner_mm = to_partner.norm();
        const Eigen::Vector3d l = to_partner / partner_mm;
        if (cos_in < cos_max || n.dot(l) < cos_max) {
          ++result.stats.rejected_incidence;
          continue;
        }
        candidates.push_back({cell, x, cos_in});
        offline::Ray shadow;
        shadow.origin_mm = x;
        shadow.direction = l;
        shadow.t_min_mm = shadow_offset_mm;
        shadow.t_max_mm = partner_mm;
        shadows.push_back(shadow);
      }
      shadow_hits.resize(shadows.size());
      scene.intersect(shadows, shadow_hits);
      for (std::size_t k = 0; k < candidates.size(); ++k) {
        if (shadow_hits[k].hit()) {
          ++result.stats.occluded;
          continue;
        }
        const Candidate& cand = candidates[k];
        const Eigen::Vector3d& dir = rays[cand.cell - first_cell].direction;
        const double sigma_mm =
            options.sigma0_mm * std::min(1.0 / cand.cos_incidence, options.max_sigma_factor);
        const double error_mm = sigma_mm * standard_normal(options.seed, pose + 1, cand.cell);
        measured.point[cand.cell] = static_cast<std::int32_t>(points.size());
        points.push_back(cand.point_mm + error_mm * dir);
        result.ray_dirs.push_back(dir);
        result.pose_of_point.push_back(static_cast<std::uint32_t>(pose));
      }
    }
    const double factor = options.mesh_edge_factor;
    measured.edge_limit_mm = [&grid, factor](const Eigen::Vector3d& p) {
      return factor * grid.local_spacing_mm(p);
    };
    grids.push_back(std::move(measured));
    if (options.progress) options.progress(pose, result.poses.size(), points.size());
  }
  result.stats.points = points.size();

  std::vector<Eigen::Vector3d>& normals = result.cloud.normals;
  normals.resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    normals[i] = -result.ray_dirs[i];
  if (options.estimate_normals) {
    for (const detail::MeasuredGrid& g : grids)
      detail::estimate_grid_normals(g, points, result.ray_dirs, normals);
  }
  if (options.build_mesh) {
    for (const detail::MeasuredGrid& g : grids)
      detail::triangulate_grid(g, points, result.ray_dirs, result.mesh.triangles);
  }

  if (options.registration_error) {
    result.registration_error = *options.registration_error;
    const Eigen::Matrix3d rotation = result.registration_error.linear();
    for (std::size_t i = 0; i < points.size(); ++i) {
      points[i] = result.registration_error * points[i];
      normals[i] = rotation * normals[i];
    }
  }
  if (options.build_mesh) {
    result.mesh.vertices_mm = points;
    result.mesh.normals = normals;
  }
  return result;
}

}  // namespace truecut::sim::measure
