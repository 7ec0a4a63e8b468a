#include "truecut/offline/scan_check.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include <tbb/parallel_for.h>

#include "truecut/offline/mesh_geometry.hpp"
#include "truecut/offline/ray_scene.hpp"
#include "truecut/rt/number_format.hpp"

namespace truecut::offline {

namespace {

constexpr double kSearchLimitMm = 100.0;

// Distance from p to the mesh, searched in radii growing by 4 from first_mm;
// kSearchLimitMm when nothing is that close.
double distance_to_mesh_mm(const RayScene& scene, const TriangleMesh& mesh,
                           const Eigen::Vector3d& p, double first_mm,
                           std::vector<std::uint32_t>& found) {
  for (double r = first_mm; r <= 4 * kSearchLimitMm; r *= 4) {
    found.clear();
    scene.triangles_within(p, r, found);
    if (found.empty()) continue;
    double best = kSearchLimitMm;
    for (std::uint32_t t : found) {
      const auto& [a, b, c] = mesh.triangles[t];
      best = std::min(best, (closest_point_on_triangle(p, mesh.vertices_mm[a], mesh.vertices_mm[b],
                                                       mesh.vertices_mm[c]) -
                             p)
                                .norm());
    }
    return best;
  }
  return kSearchLimitMm;
}

std::string motion_text(const RigidTransformReport& m) {
  return rt::format_printf("translation %.3f %.3f %.3f mm, rotation %.4f deg", m.translation_mm.x(),
                           m.translation_mm.y(), m.translation_mm.z(), m.rotation_angle_deg);
}

}  // namespace

double max_displacement_on_mesh_mm(const TriangleMesh& mesh, const Eigen::Isometry3d& t) {
  if (mesh.vertices_mm.empty()) return 0.0;
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3d& v : mesh.vertices_mm)
    box.extend(v);
  double worst = 0.0;
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d p = box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(k));
    worst = std::max(worst, (t * p - p).norm());
  }
  return worst;
}

ScanCheck check_scan(const TriangleMesh& nominal, std::span<const Eigen::Vector3d> scan_points_mm,
                     const Eigen::Isometry3d& scan_to_nominal, const Eigen::Isometry3d& motion,
                     bool declared_in_frame, const ScanCheckOptions& o) {
  ScanCheck c;
  c.declared_in_frame = declared_in_frame;
  c.motion = describe_transform(motion);
  c.motion_max_displacement_mm = max_displacement_on_mesh_mm(nominal, motion);
  if (!o.enabled) return c;
  if (c.motion_max_displacement_mm > o.max_offset_mm) {
    if (declared_in_frame)
      throw ScanMismatchError(rt::format_printf(
          "the scan sits up to %.3f mm off the nominal (the best rigid fit would move it by %s), "
          "although --no-register declares it in the workpiece frame; the tolerance is "
          "--max-scan-offset %.3g mm. Leave out --no-register to register the scan, or raise "
          "--max-scan-offset if the offset is intended",
          c.motion_max_displacement_mm, motion_text(c.motion).c_str(), o.max_offset_mm));
    throw ScanMismatchError(rt::format_printf(
        "registration fits the scan to the nominal only by moving it up to %.3f mm (%s), more "
        "than --max-scan-offset %.3g mm: the scan is in another frame or of another part. Align "
        "it first, or raise --max-scan-offset if a motion that large is intended",
        c.motion_max_displacement_mm, motion_text(c.motion).c_str(), o.max_offset_mm));
  }

  const std::size_t n = scan_points_mm.size();
  const std::size_t stride = std::max<std::size_t>(1, (n + o.sample_points - 1) / o.sample_points);
  c.points_checked = (n + stride - 1) / stride;
  std::vector<std::uint8_t> is_off(c.points_checked, 0);
  const RayScene scene(nominal);
  auto point = [&](std::size_t i) -> Eigen::Vector3d {
    return scan_to_nominal * scan_points_mm[i * stride];
  };
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, c.points_checked, 256),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      std::vector<std::uint32_t> found;
                      for (std::size_t i = range.begin(); i < range.end(); ++i) {
                        found.clear();
                        scene.triangles_within(point(i), o.max_offset_mm, found);
                        is_off[i] = found.empty();
                      }
                    });
  std::vector<std::size_t> off;
  for (std::size_t i = 0; i < is_off.size(); ++i)
    if (is_off[i]) off.push_back(i);
  c.points_off = off.size();
  c.off_percent = c.points_checked ? 100.0 * double(off.size()) / double(c.points_checked) : 0.0;
  if (!off.empty()) {
    // The median distance from an even subset of the points off the nominal
    // (a search far from the mesh visits many triangles).
    constexpr std::size_t kMedianPoints = 255;
    const std::size_t step = std::max<std::size_t>(1, off.size() / kMedianPoints);
    std::vector<double> d;
    std::vector<std::uint32_t> found;
    for (std::size_t k = 0; k < off.size(); k += step)
      d.push_back(distance_to_mesh_mm(scene, nominal, point(off[k]), 4 * o.max_offset_mm, found));
    std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
    c.off_median_distance_mm = d[d.size() / 2];
  }
  if (c.off_percent > o.max_off_percent)
    throw ScanMismatchError(rt::format_printf(
        "%.1f %% of the scan's points (%zu of %zu checked) lie farther than --max-scan-offset "
        "%.3g mm from the nominal (their median distance %.3f mm), more than --max-scan-outliers "
        "%.3g %%: a scan of another part, or not in the nominal's frame%s. Crop the scan to the "
        "part, or raise --max-scan-outliers or --max-scan-offset if this is intended",
        c.off_percent, c.points_off, c.points_checked, o.max_offset_mm, c.off_median_distance_mm,
        o.max_off_percent, declared_in_frame ? " (--no-register declares it in the frame)" : ""));
  return c;
}

}  // namespace truecut::offline
