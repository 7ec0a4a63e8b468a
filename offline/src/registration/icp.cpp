#include "geometry/sharp_edges.hpp"
#include "registration/least_squares6.hpp"
#include "spatial/kd_tree.hpp"
#include "spatial/shared_scan_tree.hpp"
#include "truecut/offline/compensation_significance.hpp"
#include "truecut/offline/mesh_geometry.hpp"
#include "truecut/offline/registration.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace truecut::offline {

namespace {

using registration::Matrix6d;
using registration::Vector6d;

constexpr double kDeg = 180.0 / M_PI;

struct Sample {
  Eigen::Vector3d q;  // on the nominal surface
  Eigen::Vector3d n;  // its face normal
};

// Area-uniform, deterministic: sample k falls at cumulative area
// (k + ½)/N · A, at a point of the triangle given by the R2 low-discrepancy
// sequence (Roberts 2018), so samples neither cluster nor depend on a seed.
std::vector<Sample> sample_surface(const TriangleMesh& mesh, std::span<const std::uint32_t> tris,
                                   std::size_t count) {
  const std::vector<Eigen::Vector3d> normals = face_normals(mesh);
  std::vector<double> cumulative;
  cumulative.reserve(tris.size());
  double total = 0.0;
  for (std::uint32_t t : tris) {
    const auto& [a, b, c] = mesh.triangles[t];
    total += 0.5 * (mesh.vertices_mm[b] - mesh.vertices_mm[a])
                       .cross(mesh.vertices_mm[c] - mesh.vertices_mm[a])
                       .norm();
    cumulative.push_back(total);
  }
  std::vector<Sample> out;
  if (!(total > 0.0)) return out;
  out.reserve(count);
  constexpr double g1 = 0.7548776662466927, g2 = 0.5698402909980532;
  for (std::size_t k = 0; k < count; ++k) {
    const double at = (static_cast<double>(k) + 0.5) / static_cast<double>(count) * total;
    const std::size_t i = std::min<std::size_t>(
        std::upper_bound(cumulative.begin(), cumulative.end(), at) - cumulative.begin(),
        tris.size() - 1);
    double u = std::fmod(0.5 + g1 * static_cast<double>(k + 1), 1.0);
    double v = std::fmod(0.5 + g2 * static_cast<double>(k + 1), 1.0);
    if (u + v > 1.0) {
      u = 1.0 - u;
      v = 1.0 - v;
    }
    const auto& [a, b, c] = mesh.triangles[tris[i]];
    const Eigen::Vector3d& pa = mesh.vertices_mm[a];
    out.push_back(
        {pa + u * (mesh.vertices_mm[b] - pa) + v * (mesh.vertices_mm[c] - pa), normals[tris[i]]});
  }
  return out;
}

struct Pair {
  bool found = false;
  Eigen::Vector3d x;  // the scan point, moved by the current transform
  double r = 0.0;     // (x − q)·n
};

// Nearest scan points of the samples from the previous iteration: the k
// nearest around the sample's last query point `at`, and `reach`, a radius
// within which every scan point is in the list. Once the pose moves by
// less than the gap between the nearest and the k-th point, the nearest
// scan point of the moved query is among the list; it is then found there
// (with the tree's tie rule) instead of in the tree: the same point, at a
// fraction of the cost.
struct NeighbourCache {
  static constexpr std::size_t k = 8;
  std::vector<Eigen::Vector3d> at;
  std::vector<double> reach;
  std::vector<std::uint32_t> index;  // k per sample
  std::vector<std::uint8_t> count;
  std::vector<std::uint8_t> filled;  // 0: nothing cached yet
};

// The tree's nearest(q, max_distance) from the cached list when the list
// provably holds it; false when the tree must be asked.
bool nearest_from_cache(const NeighbourCache& c, std::size_t i, const Eigen::Vector3d& q,
                        std::span<const Eigen::Vector3d> scan, double max_distance,
                        spatial::KdTree::Nearest& out) {
  if (!c.filled[i]) return false;
  spatial::KdTree::Nearest best;
  best.distance_sq = max_distance * max_distance;
  const std::uint32_t* list = &c.index[i * NeighbourCache::k];
  for (std::size_t m = 0; m < c.count[i]; ++m) {
    const double d2 = (scan[list[m]] - q).squaredNorm();
    if (d2 < best.distance_sq ||
        (d2 == best.distance_sq && best.index != spatial::KdTree::kNone && list[m] < best.index)) {
      best.distance_sq = d2;
      best.index = list[m];
    }
  }
  // Every point that could be the answer lies within sqrt(best) of q, so
  // within sqrt(best) + |q − at| of `at` (with a margin for rounding).
  const double need = (std::sqrt(best.distance_sq) + (q - c.at[i]).norm()) * (1.0 + 1e-9) + 1e-12;
  if (!(need < c.reach[i])) return false;
  out = best;
  return true;
}

void find_pairs(const std::vector<Sample>& samples, const spatial::KdTree& tree,
                std::span<const Eigen::Vector3d> scan, const Eigen::Isometry3d& T,
                double max_distance, bool reuse, NeighbourCache& cache, std::vector<Pair>& pairs) {
  const Eigen::Isometry3d inverse = T.inverse();
  pairs.resize(samples.size());
  if (reuse && cache.count.size() != samples.size()) {
    cache.at.assign(samples.size(), Eigen::Vector3d::Zero());
    cache.reach.assign(samples.size(), 0.0);
    cache.index.assign(samples.size() * NeighbourCache::k, 0);
    cache.count.assign(samples.size(), 0);
    cache.filled.assign(samples.size(), 0);
  }
  // The list reaches a little beyond max_distance, so that a sample without
  // a pair stays without one for small moves without asking the tree.
  const double list_radius = 1.25 * max_distance;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, samples.size(), 512),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      std::vector<spatial::KdTree::Nearest> knn;
                      for (std::size_t i = range.begin(); i != range.end(); ++i) {
                        const Eigen::Vector3d q = inverse * samples[i].q;
                        spatial::KdTree::Nearest nn;
                        if (!reuse) {
                          nn = tree.nearest(q, max_distance);
                        } else if (!nearest_from_cache(cache, i, q, scan, max_distance, nn)) {
                          tree.nearest_k(q, NeighbourCache::k, list_radius, knn);
                          cache.at[i] = q;
                          cache.filled[i] = 1;
                          cache.count[i] = static_cast<std::uint8_t>(knn.size());
                          cache.reach[i] = knn.size() == NeighbourCache::k
                                               ? std::sqrt(knn.back().distance_sq)
                                               : list_radius;
                          for (std::size_t m = 0; m < knn.size(); ++m)
                            cache.index[i * NeighbourCache::k + m] = knn[m].index;
                          nn = {};
                          if (!knn.empty() && knn.front().distance_sq < max_distance * max_distance)
                            nn = knn.front();
                        }
                        Pair& p = pairs[i];
                        p.found = nn.index != spatial::KdTree::kNone;
                        if (!p.found) continue;
                        p.x = T * scan[nn.index];
                        p.r = (p.x - samples[i].q).dot(samples[i].n);
                      }
                    });
}

double rms_of(const std::vector<Pair>& pairs, std::size_t* count) {
  double sum = 0.0;
  std::size_t n = 0;
  for (const Pair& p : pairs) {
    if (!p.found) continue;
    sum += p.r * p.r;
    ++n;
  }
  if (count) *count = n;
  return n ? std::sqrt(sum / static_cast<double>(n)) : 0.0;
}

double robust_scale(const std::vector<Pair>& pairs, double floor_mm) {
  std::vector<double> a;
  a.reserve(pairs.size());
  for (const Pair& p : pairs) {
    if (p.found) a.push_back(std::abs(p.r));
  }
  if (a.empty()) return floor_mm;
  auto mid = a.begin() + static_cast<std::ptrdiff_t>(a.size() / 2);
  std::nth_element(a.begin(), mid, a.end());
  return std::max(floor_mm, 1.4826 * *mid);
}

double weight(RobustKernel kernel, double r, double sigma) {
  switch (kernel) {
    case RobustKernel::kNone:
      return 1.0;
    case RobustKernel::kHuber: {
      const double k = 1.345 * sigma;
      return std::abs(r) <= k ? 1.0 : k / std::abs(r);
    }
    case RobustKernel::kTukey: {
      const double c = 4.685 * sigma;
      if (std::abs(r) >= c) return 0.0;
      const double s = 1.0 - (r / c) * (r / c);
      return s * s;
    }
  }
  return 1.0;
}

}  // namespace

IcpResult register_scan(const TriangleMesh& nominal, std::span<const Eigen::Vector3d> scan,
                        const IcpOptions& options) {
  if (scan.empty()) throw std::invalid_argument("registration: the scan has no points");
  return register_scan(nominal, scan, options, spatial::KdTree(scan));
}

IcpResult register_scan(const TriangleMesh& nominal, std::span<const Eigen::Vector3d> scan,
                        const IcpOptions& options, const spatial::KdTree& tree) {
  if (scan.empty()) throw std::invalid_argument("registration: the scan has no points");
  std::vector<std::uint32_t> datum = options.datum_triangles;
  if (datum.empty()) {
    datum.resize(nominal.triangles.size());
    for (std::size_t t = 0; t < datum.size(); ++t)
      datum[t] = static_cast<std::uint32_t>(t);
  }
  for (std::uint32_t t : datum) {
    if (t >= nominal.triangles.size()) {
      throw std::invalid_argument("registration: datum triangle " + std::to_string(t) +
                                  " does not exist");
    }
  }
  std::vector<Sample> samples = sample_surface(nominal, datum, options.samples);
  if (options.edge_margin_mm > 0.0) {
    const geometry::SharpEdges edges(nominal, options.sharp_edge_deg, options.edge_margin_mm);
    std::erase_if(samples, [&](const Sample& s) {
      return std::isfinite(edges.distance_within(s.q, options.edge_margin_mm));
    });
  }
  if (samples.empty()) throw std::invalid_argument("registration: the datum surface has no area");

  IcpResult result;
  result.samples = samples.size();
  Eigen::Isometry3d T = options.initial;
  std::vector<Pair> pairs;
  NeighbourCache cache;
  find_pairs(samples, tree, scan, T, options.max_correspondence_mm, options.reuse_neighbours, cache,
             pairs);
  result.rms_before_mm = rms_of(pairs, nullptr);
  // The last iteration's normal matrix, scale, centroid and lever, for the
  // significance test of the whole motion.
  Matrix6d last_H = Matrix6d::Zero();
  double last_sigma = 0.0, last_L = 1.0;
  Eigen::Vector3d last_centroid = Eigen::Vector3d::Zero();

  for (int it = 0; it < options.max_iterations; ++it) {
    result.iterations = it + 1;
    const double sigma = robust_scale(pairs, options.min_robust_scale_mm);
    result.robust_scale_mm = sigma;
    // Sequential sums over a fixed order: the result does not depend on the
    // thread count.
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    double wsum = 0.0;
    std::vector<double> w(pairs.size(), 0.0);
    for (std::size_t i = 0; i < pairs.size(); ++i) {
      if (!pairs[i].found) continue;
      w[i] = weight(options.kernel, pairs[i].r, sigma);
      centroid += w[i] * pairs[i].x;
      wsum += w[i];
    }
    if (!(wsum > 0.0)) break;
    centroid /= wsum;
    double spread = 0.0;
    for (std::size_t i = 0; i < pairs.size(); ++i) {
      if (w[i] > 0.0) spread += w[i] * (pairs[i].x - centroid).squaredNorm();
    }
    // Rotation unknowns in units of this length, so rotation and translation
    // eigenvalues of H are comparable.
    const double L = std::max(std::sqrt(spread / wsum), 1e-9);
    Matrix6d H = Matrix6d::Zero();
    Vector6d g = Vector6d::Zero();
    for (std::size_t i = 0; i < pairs.size(); ++i) {
      if (w[i] <= 0.0) continue;
      Vector6d J;
      J.head<3>() = (pairs[i].x - centroid).cross(samples[i].n) / L;
      J.tail<3>() = samples[i].n;
      H.selfadjointView<Eigen::Upper>().rankUpdate(J, w[i]);
      g -= w[i] * pairs[i].r * J;
    }
    H.triangularView<Eigen::StrictlyLower>() = H.transpose();
    last_H = H;
    last_sigma = sigma;
    last_L = L;
    last_centroid = centroid;
    const registration::Solution6 s = registration::solve_in_determined_subspace(H, g);
    result.determined_directions = s.rank;
    const Eigen::Vector3d omega = s.x.head<3>() / L;
    const Eigen::Vector3d tau = s.x.tail<3>();
    const double angle = omega.norm();
    const Eigen::Matrix3d R = angle > 0.0
                                  ? Eigen::AngleAxisd(angle, omega / angle).toRotationMatrix()
                                  : Eigen::Matrix3d::Identity();
    Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
    step.linear() = R;
    step.translation() = centroid + tau - R * centroid;
    T = step * T;
    find_pairs(samples, tree, scan, T, options.max_correspondence_mm, options.reuse_neighbours,
               cache, pairs);
    // Near the optimum, noisy scan points trade places as nearest neighbours
    // and the pose jitters by about its standard error, σ/√Σw (rotation:
    // divided by L); steps that small are noise, not progress.
    const double noise_mm = sigma / std::sqrt(wsum);
    if (tau.norm() < std::max(options.converged_translation_mm, noise_mm) &&
        angle * kDeg < std::max(options.converged_rotation_deg, noise_mm / L * kDeg)) {
      result.converged = true;
      break;
    }
  }
  // Rotations composed many times drift from orthonormal by rounding.
  T.linear() = Eigen::Quaterniond(T.linear()).normalized().toRotationMatrix();
  if (options.significance_level > 0.0 && result.determined_directions > 0 && last_sigma > 0.0) {
    // The motion from the start pose, about the last centroid, in the
    // unknowns of the normal equations (rotation × L, translation).
    const Eigen::Isometry3d motion = T * options.initial.inverse();
    const Eigen::AngleAxisd aa(motion.linear());
    Vector6d x;
    x.head<3>() = aa.angle() * aa.axis() * last_L;
    x.tail<3>() = motion * last_centroid - last_centroid;
    result.motion_chi2 = x.dot(last_H * x) / (last_sigma * last_sigma);
    result.motion_threshold =
        chi2_quantile_upper(options.significance_level, result.determined_directions);
    if (result.motion_chi2 <= result.motion_threshold) {
      result.applied = false;
      T = options.initial;
      find_pairs(samples, tree, scan, T, options.max_correspondence_mm, options.reuse_neighbours,
                 cache, pairs);
    }
  }
  result.scan_to_nominal = T;
  result.transform = describe_transform(T);
  result.rms_after_mm = rms_of(pairs, &result.correspondences);
  return result;
}

}  // namespace truecut::offline
