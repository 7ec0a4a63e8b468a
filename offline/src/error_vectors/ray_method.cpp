#include "geometry/sharp_edges.hpp"
#include "truecut/offline/error_vectors.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <stdexcept>

namespace truecut::offline {

namespace {

// Each ray starts this far behind the point, so a scanned surface through the
// point itself is found whatever the float rounding in Embree.
constexpr double kOverlapMm = 1e-3;
// Distances to an edge up to this count as "on the edge".
constexpr double kOnEdgeMm = 1e-9;

void check_points(const CompensationPoints& points) {
  const std::size_t n = points.size();
  if (points.normals.size() != n || points.surface_ids.size() != n ||
      points.triangles.size() != n) {
    throw std::invalid_argument(
        "compensation points: positions, normals, surface ids and "
        "triangles differ in number");
  }
}

ErrorVectors empty_result(std::size_t n) {
  ErrorVectors e;
  e.support_begin.assign(n + 1, 0);
  e.vectors_mm.assign(n, Eigen::Vector3d::Zero());
  e.status.assign(n, ErrorStatus::kValid);
  e.normal_mm.assign(n, 0.0);
  return e;
}

}  // namespace

ErrorVectors error_vectors_by_rays(const TriangleMesh& nominal, const CompensationPoints& points,
                                   const RayScene& scan, const RayMethodOptions& options) {
  check_points(points);
  const std::size_t n = points.size();
  ErrorVectors e = empty_result(n);

  const double exclusion = std::max(options.edge_exclusion_mm, kOnEdgeMm);
  const geometry::SharpEdges edges(nominal, options.sharp_edge_deg, exclusion);
  std::vector<std::uint8_t> on_edge(n, 0);
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, n, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          on_edge[i] = std::isfinite(edges.distance_within(points.positions_mm[i], exclusion));
        }
      });

  // Two rays per point that is not on an edge: along +n and along −n.
  std::vector<std::uint32_t> cast;
  for (std::size_t i = 0; i < n; ++i) {
    if (on_edge[i]) {
      e.status[i] = ErrorStatus::kNominalEdge;
    } else {
      cast.push_back(static_cast<std::uint32_t>(i));
    }
  }
  std::vector<Ray> rays(2 * cast.size());
  for (std::size_t k = 0; k < cast.size(); ++k) {
    const Eigen::Vector3d& p = points.positions_mm[cast[k]];
    const Eigen::Vector3d& nn = points.normals[cast[k]];
    rays[2 * k] = {p - kOverlapMm * nn, nn, 0.0, options.max_distance_mm + kOverlapMm};
    rays[2 * k + 1] = {p + kOverlapMm * nn, -nn, 0.0, options.max_distance_mm + kOverlapMm};
  }
  std::vector<RayHit> hits(rays.size());
  scan.intersect(rays, hits, {options.batch, true});

  const double cos_grazing = std::cos(options.grazing_angle_deg * M_PI / 180.0);
  std::vector<std::uint32_t> hit_triangle(n, RayHit::kMiss);
  std::vector<Eigen::Vector3d> hit_weight(n);
  for (std::size_t k = 0; k < cast.size(); ++k) {
    const std::size_t i = cast[k];
    const RayHit& up = hits[2 * k];
    const RayHit& down = hits[2 * k + 1];
    const double s_up = up.hit() ? up.distance_mm - kOverlapMm : INFINITY;
    const double s_down = down.hit() ? -(down.distance_mm - kOverlapMm) : -INFINITY;
    if (!up.hit() && !down.hit()) {
      e.status[i] = ErrorStatus::kNoHit;
      continue;
    }
    const bool take_up = std::abs(s_up) <= std::abs(s_down);
    const RayHit& h = take_up ? up : down;
    const double s = take_up ? s_up : s_down;
    const Eigen::Vector3d& nn = points.normals[i];
    const double c = nn.dot(h.normal);
    if (options.reject_back_faces && c < 0.0) {
      e.status[i] = ErrorStatus::kBackFace;
    } else if (std::abs(c) < cos_grazing) {
      e.status[i] = ErrorStatus::kGrazing;
    } else {
      e.normal_mm[i] = s;
      e.vectors_mm[i] = s * nn;
      hit_triangle[i] = h.triangle;
      hit_weight[i] = {1.0 - h.u - h.v, h.u, h.v};
    }
  }
  e.support_begin.assign(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    e.support_begin[i] = static_cast<std::uint32_t>(e.support_point.size());
    if (hit_triangle[i] == RayHit::kMiss) continue;
    for (int c = 0; c < 3; ++c) {
      e.support_point.push_back(scan.triangle(hit_triangle[i])[c]);
      e.support_weight.push_back(static_cast<float>(hit_weight[i][c]));
    }
  }
  e.support_begin[n] = static_cast<std::uint32_t>(e.support_point.size());
  return e;
}

}  // namespace truecut::offline
