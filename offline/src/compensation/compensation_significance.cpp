#include "truecut/offline/compensation_significance.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>

#include "spatial/kd_tree.hpp"
#include "spatial/shared_scan_tree.hpp"

namespace truecut::offline {

namespace {

constexpr double kMadToSigma = 1.4826;
// Neighbours per residual, and the candidates they are chosen from.
constexpr std::size_t kNeighbours = 8;
constexpr std::size_t kCloudCandidates = 16;
constexpr double kCos45 = 0.70710678118654752;

// The neighbours of a scan point that its noise residual is taken against:
// the kNeighbours nearest in the tangent plane (distance across the normal)
// among the point's two rings of mesh neighbours, or among its
// kCloudCandidates nearest cloud points. Chosen across the normal, so the
// choice does not depend on the noise along it: a scan mesh split along the
// shorter diagonal joins points whose noise happens to agree, and a
// residual against the ring itself came out 20 % low (k-dependent: ±50 %)
// on the simulated scanner. Candidates on another face are left out: a
// mesh neighbour only when one of its triangles reached lies within 45° of
// the normal, a cloud point only when it lies within 45° of the tangent
// plane (near an edge a point of the other face is close across the normal
// and far along it).
class Neighbours {
 public:
  // Rings are gathered for the listed points only, in two passes over the
  // triangles (the points' triangles, then their neighbours' triangles).
  // shared_tree: of scan.vertices_mm, or null (then built here if needed).
  Neighbours(const TriangleMesh& scan, std::span<const std::uint32_t> asked,
             const spatial::KdTree* shared_tree)
      : scan_(scan) {
    if (scan.triangles.empty()) {
      tree_ = shared_tree ? shared_tree : &own_tree_.emplace(scan.vertices_mm);
      return;
    }
    std::vector<std::uint8_t> wanted(scan.vertices_mm.size(), 0);
    for (std::uint32_t v : asked)
      wanted[v] = 1;
    index_triangles_of(wanted);
    for (std::uint32_t v : asked)
      ring(v, [&](std::uint32_t, std::uint32_t c) { wanted[c] = 1; });
    index_triangles_of(wanted);
  }

  // n·(p − mean of the neighbours) / √(1 + 1/k): the noise of one point.
  // Empty with fewer than 3 neighbours.
  std::optional<double> residual(std::uint32_t v, const Eigen::Vector3d& n) const {
    const Eigen::Vector3d& p = scan_.vertices_mm[v];
    std::vector<std::uint32_t> candidates;
    if (tree_) {
      std::vector<spatial::KdTree::Nearest> near;
      tree_->nearest_k(p, kCloudCandidates + 1, std::numeric_limits<double>::infinity(), near);
      for (const auto& q : near)
        candidates.push_back(q.index);
    } else {
      std::vector<std::uint32_t> first;
      auto take = [&](std::uint32_t t, std::uint32_t c, std::vector<std::uint32_t>* also) {
        const auto& [a, b, d] = scan_.triangles[t];
        const Eigen::Vector3d& x = scan_.vertices_mm[a];
        const Eigen::Vector3d face = (scan_.vertices_mm[b] - x).cross(scan_.vertices_mm[d] - x);
        if (std::abs(face.dot(n)) >= kCos45 * face.norm()) candidates.push_back(c);
        if (also) also->push_back(c);
      };
      ring(v, [&](std::uint32_t t, std::uint32_t c) { take(t, c, &first); });
      std::sort(first.begin(), first.end());
      first.erase(std::unique(first.begin(), first.end()), first.end());
      for (std::uint32_t c : first)
        ring(c, [&](std::uint32_t t, std::uint32_t d) { take(t, d, nullptr); });
      std::sort(candidates.begin(), candidates.end());
      candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
    }
    std::vector<std::pair<double, std::uint32_t>> across;  // tangential distance², point
    for (std::uint32_t c : candidates) {
      if (c == v) continue;
      const Eigen::Vector3d d = scan_.vertices_mm[c] - p;
      const double along = d.dot(n), across2 = d.squaredNorm() - along * along;
      if (tree_ && along * along > across2) continue;  // beyond 45° of the tangent plane
      across.push_back({across2, c});
    }
    const std::size_t k = std::min(kNeighbours, across.size());
    if (k < 3) return std::nullopt;
    std::partial_sort(across.begin(), across.begin() + static_cast<std::ptrdiff_t>(k),
                      across.end());
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < k; ++i)
      sum += scan_.vertices_mm[across[i].second];
    const double r = n.dot(p - sum / static_cast<double>(k));
    return r / std::sqrt(1.0 + 1.0 / static_cast<double>(k));
  }

 private:
  // Appends to triangles_of_ the triangles of every wanted point not yet indexed.
  void index_triangles_of(const std::vector<std::uint8_t>& wanted) {
    for (std::size_t t = 0; t < scan_.triangles.size(); ++t)
      for (std::uint32_t v : scan_.triangles[t])
        if (wanted[v] && !done_.count(v)) triangles_of_[v].push_back(static_cast<std::uint32_t>(t));
    for (const auto& [v, list] : triangles_of_)
      done_.insert(v);
  }
  // take(triangle, corner) for every other corner of v's triangles.
  template <typename F>
  void ring(std::uint32_t v, F&& take) const {
    const auto it = triangles_of_.find(v);
    if (it == triangles_of_.end()) return;
    for (std::uint32_t t : it->second)
      for (std::uint32_t c : scan_.triangles[t])
        if (c != v) take(t, c);
  }

  const TriangleMesh& scan_;
  std::optional<spatial::KdTree> own_tree_;
  const spatial::KdTree* tree_ = nullptr;
  std::unordered_map<std::uint32_t, std::vector<std::uint32_t>> triangles_of_;
  std::unordered_set<std::uint32_t> done_;
};

double robust_sigma(std::vector<double> abs_residuals) {
  if (abs_residuals.empty()) return 0.0;
  auto mid = abs_residuals.begin() + static_cast<std::ptrdiff_t>(abs_residuals.size() / 2);
  std::nth_element(abs_residuals.begin(), mid, abs_residuals.end());
  return kMadToSigma * *mid;
}

// Upper-tail quantile of the standard normal distribution, by bisection on
// erfc (to 1e-12).
double normal_quantile_upper(double upper_tail) {
  double lo = -40.0, hi = 40.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (0.5 * std::erfc(mid / std::sqrt(2.0)) > upper_tail) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  return 0.5 * (lo + hi);
}

}  // namespace

double chi2_quantile_upper(double upper_tail, double dof) {
  if (!(upper_tail > 0.0 && upper_tail < 1.0) || !(dof > 0.0))
    throw std::invalid_argument("chi2_quantile_upper: tail in (0, 1) and dof > 0 required");
  const double z = normal_quantile_upper(upper_tail);
  const double a = 2.0 / (9.0 * dof);
  const double c = 1.0 - a + z * std::sqrt(a);
  return dof * std::max(c, 0.0) * std::max(c, 0.0) * std::max(c, 0.0);
}

bool SignificanceResult::compensated(std::int32_t surface) const {
  for (const SurfaceSignificance& s : surfaces)
    if (s.surface == surface) return s.compensated;
  return true;
}

namespace {

SignificanceResult test_significance(const CompensationPoints& points, const ErrorVectors& errors,
                                     const TriangleMesh& scan,
                                     const Eigen::Isometry3d& world_from_scan,
                                     const SignificanceOptions& o,
                                     const spatial::KdTree* scan_tree) {
  if (!(o.significance_level >= 0.0 && o.significance_level < 1.0) || !(o.patch_mm > 0.0) ||
      !(o.noise_mm >= 0.0) || !std::isfinite(o.patch_mm) || !std::isfinite(o.noise_mm))
    throw std::invalid_argument(
        "significance test: level in [0, 1), patch > 0 and noise >= 0 required");
  const std::size_t n = points.size();
  if (errors.size() != n || points.surface_ids.size() != n || errors.support_begin.size() != n + 1)
    throw std::invalid_argument("significance test: error vectors do not fit the points");
  for (std::uint32_t v : errors.support_point)
    if (v >= scan.vertices_mm.size())
      throw std::invalid_argument("significance test: a support point is not in the scan");

  // Surfaces with valid points.
  std::map<std::int32_t, std::vector<std::uint32_t>> of_surface;  // valid points
  for (std::size_t i = 0; i < n; ++i)
    if (errors.valid(i)) of_surface[points.surface_ids[i]].push_back(static_cast<std::uint32_t>(i));
  SignificanceResult out;
  out.tested = o.significance_level > 0.0;

  // Per surface: its distinct support points, and for the noise up to
  // kNoisePoints of them (evenly spread over the list) with the normal, in
  // the scan's frame, of the first valid point that uses each.
  const Eigen::Matrix3d to_scan = world_from_scan.linear().transpose();
  struct SurfaceSupport {
    std::vector<std::uint32_t> points;       // distinct support points
    std::vector<Eigen::Vector3d> direction;  // per support point
  };
  std::vector<SurfaceSupport> support(of_surface.size());
  {
    std::vector<std::int32_t> seen_by(scan.vertices_mm.size(), -1);
    std::size_t k = 0;
    for (const auto& [id, valid_points] : of_surface) {
      for (std::uint32_t i : valid_points)
        for (std::uint32_t e = errors.support_begin[i]; e < errors.support_begin[i + 1]; ++e) {
          const std::uint32_t v = errors.support_point[e];
          if (seen_by[v] == static_cast<std::int32_t>(k)) continue;
          seen_by[v] = static_cast<std::int32_t>(k);
          support[k].points.push_back(v);
          // The noise is measured along this point's normal only where the
          // scan point lies within 45° of its tangent plane: a sphere's
          // support at an edge holds points of the other face.
          // A sphere at an edge or corner fits several planes, and the
          // point's normal is none of them.
          const bool one_plane =
              errors.sphere_case.empty() || errors.sphere_case[i] == SphereCase::kSurface;
          const Eigen::Vector3d d = world_from_scan * scan.vertices_mm[v] - points.positions_mm[i];
          const double along = d.dot(points.normals[i]);
          const bool on_plane = one_plane && along * along <= d.squaredNorm() - along * along;
          support[k].direction.push_back(on_plane ? Eigen::Vector3d(to_scan * points.normals[i])
                                                  : Eigen::Vector3d::Zero());
        }
      ++k;
    }
  }
  constexpr std::size_t kNoisePoints = 2000;
  std::vector<std::vector<double>> surface_residuals(support.size());
  if (o.noise_mm == 0.0) {
    std::vector<std::uint32_t> asked;
    std::vector<std::pair<std::size_t, std::size_t>> which;  // surface, index into its support
    for (std::size_t k = 0; k < support.size(); ++k) {
      const std::size_t m = support[k].points.size();
      const std::size_t take = std::min(m, kNoisePoints);
      for (std::size_t q = 0; q < take; ++q) {
        const std::size_t idx = q * m / take;
        if (support[k].direction[idx].isZero()) continue;  // off the point's plane
        asked.push_back(support[k].points[idx]);
        which.push_back({k, idx});
      }
    }
    const Neighbours neighbours(scan, asked, scan_tree);
    std::vector<double> residual(asked.size(), std::nan(""));
    tbb::parallel_for(std::size_t{0}, asked.size(), [&](std::size_t q) {
      const auto& [k, idx] = which[q];
      if (auto r = neighbours.residual(asked[q], support[k].direction[idx]))
        residual[q] = std::abs(*r);
    });
    std::vector<double> all;
    for (std::size_t q = 0; q < asked.size(); ++q) {
      if (!std::isfinite(residual[q])) continue;
      surface_residuals[which[q].first].push_back(residual[q]);
      all.push_back(residual[q]);
    }
    out.noise_points = all.size();
    out.pooled_noise_mm = robust_sigma(std::move(all));
  } else {
    out.pooled_noise_mm = o.noise_mm;
  }

  // Σ_v (W_v / n)² of a group of valid points, W_v the sum of scan point v's
  // weights over them: × σ², the variance of their mean error.
  std::vector<double> weight_of(scan.vertices_mm.size(), 0.0);
  std::vector<std::uint8_t> is_touched(scan.vertices_mm.size(), 0);
  std::vector<std::uint32_t> touched;
  auto variance_factor = [&](std::span<const std::uint32_t> group) {
    touched.clear();
    for (std::uint32_t i : group)
      for (std::uint32_t e = errors.support_begin[i]; e < errors.support_begin[i + 1]; ++e) {
        const std::uint32_t v = errors.support_point[e];
        if (!is_touched[v]) {
          is_touched[v] = 1;
          touched.push_back(v);
        }
        weight_of[v] += errors.support_weight[e];
      }
    double sum = 0.0;
    const double size = static_cast<double>(group.size());
    for (std::uint32_t v : touched) {
      sum += (weight_of[v] / size) * (weight_of[v] / size);
      weight_of[v] = 0.0;
      is_touched[v] = 0;
    }
    return sum;
  };

  std::size_t k = 0;
  for (const auto& [id, valid_points] : of_surface) {
    SurfaceSignificance s;
    s.surface = id;
    s.valid_points = valid_points.size();
    s.scan_points = support[k].points.size();
    if (o.noise_mm > 0.0) {
      s.noise_mm = o.noise_mm;
    } else if (surface_residuals[k].size() >= o.min_noise_points) {
      s.noise_mm = robust_sigma(std::move(surface_residuals[k]));
    } else {
      s.noise_mm = out.pooled_noise_mm;
      s.pooled_noise = true;
    }
    ++k;
    // Cubes from the corner of the surface's measured region, so a surface
    // smaller than a cube is one patch.
    Eigen::Vector3d corner = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    for (std::uint32_t i : valid_points)
      corner = corner.cwiseMin(points.positions_mm[i]);
    std::map<std::array<std::int64_t, 3>, std::vector<std::uint32_t>> patches;
    double sum_mm = 0.0;
    for (std::uint32_t i : valid_points) {
      const Eigen::Vector3d u = (points.positions_mm[i] - corner) / o.patch_mm;
      patches[{static_cast<std::int64_t>(std::floor(u.x())),
               static_cast<std::int64_t>(std::floor(u.y())),
               static_cast<std::int64_t>(std::floor(u.z()))}]
          .push_back(i);
      sum_mm += errors.normal_mm[i];
    }
    s.mean_normal_mm = sum_mm / static_cast<double>(valid_points.size());
    s.mean_uncertainty_mm = s.noise_mm * std::sqrt(variance_factor(valid_points));
    s.patches = patches.size();
    for (const auto& [key, group] : patches) {
      double mean = 0.0;
      for (std::uint32_t i : group)
        mean += errors.normal_mm[i];
      mean /= static_cast<double>(group.size());
      const double variance = s.noise_mm * s.noise_mm * variance_factor(group);
      // A noiseless scan (or a support without weight) leaves no doubt.
      s.chi2 += variance > 0.0 ? mean * mean / variance
                               : (mean != 0.0 ? std::numeric_limits<double>::infinity() : 0.0);
    }
    if (out.tested) {
      const double dof = static_cast<double>(s.patches);
      s.threshold = std::max(chi2_quantile_upper(o.significance_level, dof), 2.0 * dof);
      s.compensated = s.chi2 > s.threshold;
    }
    out.surfaces.push_back(s);
  }
  return out;
}

}  // namespace

SignificanceResult test_compensation_significance(const CompensationPoints& points,
                                                  const ErrorVectors& errors,
                                                  const TriangleMesh& scan,
                                                  const Eigen::Isometry3d& world_from_scan,
                                                  const SignificanceOptions& o) {
  return test_significance(points, errors, scan, world_from_scan, o, nullptr);
}

SignificanceResult test_compensation_significance(const CompensationPoints& points,
                                                  const ErrorVectors& errors,
                                                  const TriangleMesh& scan,
                                                  const Eigen::Isometry3d& world_from_scan,
                                                  const SignificanceOptions& o,
                                                  const spatial::KdTree& scan_tree) {
  return test_significance(points, errors, scan, world_from_scan, o, &scan_tree);
}

}  // namespace truecut::offline
