#include "spatial/kd_tree.hpp"
#include "spatial/shared_scan_tree.hpp"
#include "truecut/offline/error_vectors.hpp"
#include "truecut/offline/mesh_geometry.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>

namespace truecut::offline {

namespace {

// Triangles whose closest point is this close to the compensation point pass
// through it.
constexpr double kThroughPointMm = 1e-7;
constexpr int kMaxReassignments = 10;

// A nominal plane near the point: a cluster of nominal triangles, and the
// plane fitted to the cloud points assigned to it.
struct Plane {
  Eigen::Vector3d normal_sum = Eigen::Vector3d::Zero();  // of its triangles
  Eigen::Vector3d nominal_normal = Eigen::Vector3d::Zero();
  Eigen::Vector3d nominal_origin = Eigen::Vector3d::Zero();
  bool through_point = false;
  std::size_t count = 0;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // fitted, oriented like the nominal
  bool fitted = false;

  // To the fitted plane, or before fitting to the nominal plane moved by
  // `shift`.
  double distance(const Eigen::Vector3d& x, const Eigen::Vector3d& shift) const {
    return fitted ? std::abs((x - centroid).dot(normal))
                  : std::abs((x - nominal_origin - shift).dot(nominal_normal));
  }
};

struct Scratch {
  std::vector<RayScene::NearTriangle> triangles;
  std::vector<RayScene::NearTriangle> subset_triangles;
  std::vector<std::uint32_t> cloud;
  std::vector<std::pair<std::uint32_t, float>> support;
  std::vector<Plane> planes;
  std::vector<int> assigned;
  Eigen::Vector3d shift = Eigen::Vector3d::Zero();  // local translation estimate
};

struct Context {
  const TriangleMesh& nominal;
  const std::vector<Eigen::Vector3d>& face_normal;
  const RayScene& nominal_scene;
  // When the facets are thinned: a scene of the subset, and each of its
  // triangles' index in the nominal.
  const RayScene* subset_scene;
  std::span<const std::uint32_t> nominal_triangle_of;
  const spatial::KdTree& cloud_tree;
  const Eigen::Isometry3d& tree_from_world;  // the tree's points are tree_from_world · cloud
  std::span<const Eigen::Vector3d> cloud;
  const SphereMethodOptions& options;
  double cos_plane;
};

// Greedy clustering of the nominal triangles within Rs: those through the
// point first, so every plane through the point has its origin there.
void cluster_nominal(const Context& c, const Eigen::Vector3d& P, Scratch& s) {
  s.planes.clear();
  const double offset_tol = 0.25 * c.options.radius_mm;
  for (int pass = 0; pass < 2; ++pass) {
    for (const auto& [t, x] : s.triangles) {
      const bool through = (x - P).norm() <= kThroughPointMm;
      if (through != (pass == 0)) continue;
      const Eigen::Vector3d& n = c.face_normal[t];
      if (n.isZero()) continue;
      Plane* home = nullptr;
      for (Plane& p : s.planes) {
        if (p.nominal_normal.dot(n) >= c.cos_plane &&
            std::abs((x - p.nominal_origin).dot(p.nominal_normal)) <= offset_tol) {
          home = &p;
          break;
        }
      }
      if (!home) {
        Plane p;
        p.nominal_origin = through ? P : x;
        p.through_point = through;
        s.planes.push_back(p);
        home = &s.planes.back();
      }
      home->normal_sum += n;
      home->nominal_normal = home->normal_sum.normalized();
    }
  }
}

void fit_planes(const Context& c, Scratch& s) {
  for (Plane& p : s.planes) {
    p.count = 0;
    p.centroid.setZero();
  }
  for (std::size_t k = 0; k < s.cloud.size(); ++k) {
    Plane& p = s.planes[s.assigned[k]];
    ++p.count;
    p.centroid += c.cloud[s.cloud[k]];
  }
  std::vector<Eigen::Matrix3d> cov(s.planes.size(), Eigen::Matrix3d::Zero());
  for (Plane& p : s.planes) {
    if (p.count) p.centroid /= static_cast<double>(p.count);
  }
  for (std::size_t k = 0; k < s.cloud.size(); ++k) {
    const Eigen::Vector3d d = c.cloud[s.cloud[k]] - s.planes[s.assigned[k]].centroid;
    cov[s.assigned[k]] += d * d.transpose();
  }
  for (std::size_t j = 0; j < s.planes.size(); ++j) {
    Plane& p = s.planes[j];
    p.fitted = p.count >= 3;
    if (!p.fitted) continue;
    if (!c.options.tilted_planes) {  // parallel to the nominal, through the points' centroid
      p.normal = p.nominal_normal;
      continue;
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov[j]);
    p.normal = eig.eigenvectors().col(0);  // smallest eigenvalue
    if (p.normal.dot(p.nominal_normal) < 0.0) p.normal = -p.normal;
  }
}

// Returns whether any point changed plane.
bool assign(const Context& c, Scratch& s) {
  bool changed = false;
  for (std::size_t k = 0; k < s.cloud.size(); ++k) {
    const Eigen::Vector3d& x = c.cloud[s.cloud[k]];
    int best = 0;
    double best_d = INFINITY;
    for (std::size_t j = 0; j < s.planes.size(); ++j) {
      const double d = s.planes[j].distance(x, s.shift);
      if (d < best_d) {
        best_d = d;
        best = static_cast<int>(j);
      }
    }
    changed |= s.assigned[k] != best;
    s.assigned[k] = best;
  }
  return changed;
}

// The translation that best moves the nominal planes onto their assigned
// points (point-to-plane least squares, in the directions the planes
// determine: 1 for a surface, 2 for an edge, 3 for a corner).
Eigen::Vector3d local_translation(const Context& c, const Scratch& s) {
  Eigen::Matrix3d N = Eigen::Matrix3d::Zero();
  Eigen::Vector3d r = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < s.cloud.size(); ++k) {
    const Plane& p = s.planes[s.assigned[k]];
    N += p.nominal_normal * p.nominal_normal.transpose();
    r += p.nominal_normal * (c.cloud[s.cloud[k]] - p.nominal_origin).dot(p.nominal_normal);
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(N);
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  const double top = eig.eigenvalues().maxCoeff();
  for (int j = 0; j < 3; ++j) {
    const double lambda = eig.eigenvalues()[j];
    if (lambda > 1e-6 * top) {
      const Eigen::Vector3d u = eig.eigenvectors().col(j);
      v += u * (u.dot(r) / lambda);
    }
  }
  return v;
}

// Each scan point's weight in n·v: the plane offsets b_k are means over the
// plane's points (along its normal), and n·v = gᵀ b with g from the solve
// below.
void record_support(const Scratch& s, const std::vector<int>& plane_row, const Eigen::VectorXd& g,
                    std::vector<std::pair<std::uint32_t, float>>& out) {
  out.clear();
  for (std::size_t k = 0; k < s.cloud.size(); ++k) {
    const int row = plane_row[static_cast<std::size_t>(s.assigned[k])];
    if (row < 0) continue;
    const double count =
        static_cast<double>(s.planes[static_cast<std::size_t>(s.assigned[k])].count);
    out.push_back({s.cloud[k], static_cast<float>(g[row] / count)});
  }
}

void one_point(const Context& c, const Eigen::Vector3d& P, const Eigen::Vector3d& normal,
               Scratch& s, ErrorVectors& e, std::size_t i) {
  s.support.clear();
  const double Rs = c.options.radius_mm;
  s.cloud.clear();
  c.cloud_tree.within(c.tree_from_world * P, Rs, s.cloud);
  // No sort needed: the tree, and so the order of the points, is fixed by
  // the input.
  e.points_in_sphere[i] = static_cast<std::uint32_t>(s.cloud.size());
  if (s.cloud.size() < c.options.min_points) {
    e.status[i] = ErrorStatus::kTooFewPoints;
    return;
  }
  s.triangles.clear();
  if (c.subset_scene) {
    // Every facet through the point, then the subset's other facets (the
    // query's own test, so none comes twice); both in facet order.
    c.nominal_scene.triangles_within(P, kThroughPointMm, s.triangles);
    s.subset_triangles.clear();
    c.subset_scene->triangles_within(P, Rs, s.subset_triangles);
    for (RayScene::NearTriangle t : s.subset_triangles) {
      if ((t.closest_mm - P).squaredNorm() <= kThroughPointMm * kThroughPointMm) continue;
      t.triangle = c.nominal_triangle_of[t.triangle];
      s.triangles.push_back(t);
    }
  } else {
    c.nominal_scene.triangles_within(P, Rs, s.triangles);
  }
  cluster_nominal(c, P, s);
  s.assigned.assign(s.cloud.size(), -1);
  for (Plane& p : s.planes)
    p.fitted = false;
  // Which plane a point belongs to is ambiguous near an edge when the
  // displacement is as large as the distance to the edge. So points first go
  // to the nearest nominal plane moved by the local translation estimated
  // from the current assignment, until nothing moves; then to the nearest
  // fitted plane, until nothing moves.
  s.shift.setZero();
  assign(c, s);
  if (s.planes.size() > 1) {  // one plane: nothing to sort out
    for (int round = 0; round < kMaxReassignments; ++round) {
      s.shift = local_translation(c, s);
      if (!assign(c, s)) break;
    }
    for (int round = 0; round < kMaxReassignments; ++round) {
      fit_planes(c, s);
      if (!assign(c, s)) break;
    }
  }
  fit_planes(c, s);

  // Planes through the point: X = P + Aᵀ(AAᵀ)⁻¹(b − AP) is the point of their
  // intersection nearest to P (1 plane: the projection; 2: the nearest point
  // on the edge line; 3: the corner). With 4 or more, the least-squares point,
  // each plane weighted by its point count.
  Eigen::Matrix<double, Eigen::Dynamic, 3> A(0, 3);
  Eigen::VectorXd b(0), w(0);
  int k = 0;
  std::vector<int> plane_row(s.planes.size(), -1);
  for (std::size_t j = 0; j < s.planes.size(); ++j) {
    const Plane& p = s.planes[j];
    if (!p.through_point) continue;
    plane_row[j] = k;
    if (!p.fitted || p.count < c.options.min_points) {
      e.status[i] = ErrorStatus::kTooFewPoints;
      return;
    }
    if (p.normal.dot(p.nominal_normal) < c.cos_plane) {
      e.status[i] = ErrorStatus::kPlaneTilted;
      return;
    }
    A.conservativeResize(k + 1, 3);
    b.conservativeResize(k + 1);
    w.conservativeResize(k + 1);
    A.row(k) = p.normal.transpose();
    b[k] = p.normal.dot(p.centroid) - p.normal.dot(P);
    w[k] = static_cast<double>(p.count);
    ++k;
  }
  e.sphere_case[i] = k == 1   ? SphereCase::kSurface
                     : k == 2 ? SphereCase::kEdge
                     : k == 3 ? SphereCase::kCorner
                              : SphereCase::kMulti;
  Eigen::Vector3d v;
  if (k <= 3) {
    const Eigen::MatrixXd AAt = A * A.transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(AAt);
    // Smallest eigenvalue of AAᵀ: sin² of the angle between two planes.
    if (eig.eigenvalues().minCoeff() < 1e-4) {
      e.status[i] = ErrorStatus::kIllConditioned;
      return;
    }
    v = A.transpose() * AAt.ldlt().solve(b);
    record_support(s, plane_row, AAt.ldlt().solve(A * normal), s.support);
  } else {
    const Eigen::Matrix3d N = A.transpose() * w.asDiagonal() * A;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(N);
    if (eig.eigenvalues().minCoeff() < 1e-4 * eig.eigenvalues().maxCoeff()) {
      e.status[i] = ErrorStatus::kIllConditioned;
      return;
    }
    v = N.ldlt().solve(A.transpose() * w.asDiagonal() * b);
    record_support(s, plane_row, w.asDiagonal() * (A * N.ldlt().solve(normal)), s.support);
  }
  if (v.norm() > c.options.max_displacement_ratio * Rs) {
    e.status[i] = ErrorStatus::kBeyondSphereReach;
    s.support.clear();
    return;
  }
  e.vectors_mm[i] = v;
  e.normal_mm[i] = v.dot(normal);
}

// The median of count(P) over up to 1,001 compensation points P spread
// evenly over the list.
template <class Count>
std::size_t median_over_points(const CompensationPoints& points, Count count) {
  constexpr std::size_t kProbes = 1001;
  const std::size_t n = points.size(), probes = std::min(n, kProbes);
  if (probes == 0) return 0;
  std::vector<std::size_t> counts(probes);
  for (std::size_t k = 0; k < probes; ++k)
    counts[k] = count(points.positions_mm[k * n / probes]);
  auto mid = counts.begin() + static_cast<std::ptrdiff_t>(probes / 2);
  std::nth_element(counts.begin(), mid, counts.end());
  return *mid;
}

// The median number of scan points in a sphere.
std::size_t median_points_per_sphere(const CompensationPoints& points, const spatial::KdTree& tree,
                                     const Eigen::Isometry3d& tree_from_world, double radius_mm) {
  std::vector<std::uint32_t> found;
  return median_over_points(points, [&](const Eigen::Vector3d& p) {
    found.clear();
    tree.within(tree_from_world * p, radius_mm, found);
    return found.size();
  });
}

// The median number of nominal facets in a sphere.
std::size_t median_triangles_per_sphere(const CompensationPoints& points, const RayScene& scene,
                                        double radius_mm) {
  std::vector<std::uint32_t> found;
  return median_over_points(points, [&](const Eigen::Vector3d& p) {
    found.clear();
    scene.triangles_within(p, radius_mm, found);
    return found.size();
  });
}

// Whether scan point `index` is in the subset that keeps `fraction` of the
// points: a fixed hash of the index (splitmix64), so the subset depends on
// nothing but the scan.
bool kept_in_subset(std::uint64_t index, double fraction) {
  std::uint64_t z = index + 0x9e3779b97f4a7c15ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) * 0x1.0p-53 < fraction;
}

// The facets the planes beside a point are clustered from when the spheres
// hold too many (SphereMethodOptions::max_facets_per_sphere): each facet
// kept with a probability of its area over a0 = π Rs² / bound (by a hash of
// its index), so that a sphere keeps about `bound` of the small ones; every
// facet of a0 or more; and every facet on an edge where planes part (a
// dihedral of half the plane angle or more, a boundary; of a non-manifold
// edge the two facets mesh_edges names), so that no face next to the point
// is lost however little of it reaches into the sphere. `triangle_of`: each kept facet's index.
TriangleMesh facet_subset(const TriangleMesh& nominal, const std::vector<Eigen::Vector3d>& fn,
                          const SphereMethodOptions& options,
                          std::vector<std::uint32_t>& triangle_of) {
  const std::size_t n = nominal.triangles.size();
  std::vector<std::uint8_t> keep(n, 0);
  for (const MeshEdge& edge : mesh_edges(nominal, fn)) {
    if (edge.dihedral_deg < 0.5 * options.plane_angle_deg) continue;
    if (edge.t0 != kNoTriangle) keep[edge.t0] = 1;
    if (edge.t1 != kNoTriangle) keep[edge.t1] = 1;
  }
  const std::vector<double> area = face_areas_mm2(nominal);
  const double a0 = M_PI * options.radius_mm * options.radius_mm /
                    static_cast<double>(options.max_facets_per_sphere);
  TriangleMesh subset;
  subset.vertices_mm = nominal.vertices_mm;
  triangle_of.clear();
  for (std::size_t t = 0; t < n; ++t) {
    if (!keep[t] && !kept_in_subset(t, area[t] / a0)) continue;
    subset.triangles.push_back(nominal.triangles[t]);
    triangle_of.push_back(static_cast<std::uint32_t>(t));
  }
  return subset;
}

}  // namespace

ErrorVectors error_vectors_by_spheres(const TriangleMesh& nominal, const CompensationPoints& points,
                                      std::span<const Eigen::Vector3d> cloud_mm,
                                      const SphereMethodOptions& options) {
  return error_vectors_by_spheres(nominal, points, cloud_mm, options, spatial::KdTree(cloud_mm));
}

ErrorVectors error_vectors_by_spheres(const TriangleMesh& nominal, const CompensationPoints& points,
                                      std::span<const Eigen::Vector3d> cloud_mm,
                                      const SphereMethodOptions& options,
                                      const spatial::KdTree& tree) {
  return error_vectors_by_spheres(nominal, points, cloud_mm, options, tree,
                                  Eigen::Isometry3d::Identity());
}

ErrorVectors error_vectors_by_spheres(const TriangleMesh& nominal, const CompensationPoints& points,
                                      std::span<const Eigen::Vector3d> cloud_mm,
                                      const SphereMethodOptions& options,
                                      const spatial::KdTree& tree,
                                      const Eigen::Isometry3d& world_from_tree) {
  const Eigen::Isometry3d tree_from_world = world_from_tree.inverse();
  const Eigen::Isometry3d identity = Eigen::Isometry3d::Identity();
  const std::size_t n = points.size();
  if (points.normals.size() != n) {
    throw std::invalid_argument("compensation points: positions and normals differ in number");
  }
  if (!(options.radius_mm > 0.0)) throw std::invalid_argument("sphere radius must be positive");
  ErrorVectors e;
  e.vectors_mm.assign(n, Eigen::Vector3d::Zero());
  e.status.assign(n, ErrorStatus::kValid);
  e.normal_mm.assign(n, 0.0);
  e.sphere_case.assign(n, SphereCase::kNone);
  e.points_in_sphere.assign(n, 0);

  // Thinned when the spheres hold more points than the options allow: the
  // subset's own points and tree, and each one's index in the scan.
  std::vector<Eigen::Vector3d> subset;
  std::vector<std::uint32_t> scan_index_of;
  std::optional<spatial::KdTree> subset_tree;
  if (options.max_points_per_sphere > 0) {
    const std::size_t median =
        median_points_per_sphere(points, tree, tree_from_world, options.radius_mm);
    if (median > options.max_points_per_sphere) {
      e.scan_fraction =
          static_cast<double>(options.max_points_per_sphere) / static_cast<double>(median);
      for (std::size_t j = 0; j < cloud_mm.size(); ++j) {
        if (!kept_in_subset(j, e.scan_fraction)) continue;
        subset.push_back(cloud_mm[j]);
        scan_index_of.push_back(static_cast<std::uint32_t>(j));
      }
      subset_tree.emplace(subset);
    }
  }
  const std::vector<Eigen::Vector3d> fn = face_normals(nominal);
  const RayScene nominal_scene(nominal);
  // Thinned when the spheres hold more facets than the options allow.
  std::optional<RayScene> subset_scene;
  std::vector<std::uint32_t> nominal_triangle_of;
  if (options.max_facets_per_sphere > 0) {
    e.median_facets_per_sphere =
        median_triangles_per_sphere(points, nominal_scene, options.radius_mm);
    if (e.median_facets_per_sphere > options.max_facets_per_sphere) {
      const TriangleMesh subset_mesh = facet_subset(nominal, fn, options, nominal_triangle_of);
      e.nominal_fraction = static_cast<double>(nominal_triangle_of.size()) /
                           static_cast<double>(nominal.triangles.size());
      subset_scene.emplace(subset_mesh);
    }
  }
  const Context c{nominal,
                  fn,
                  nominal_scene,
                  subset_scene ? &*subset_scene : nullptr,
                  nominal_triangle_of,
                  subset_tree ? *subset_tree : tree,
                  subset_tree ? identity : tree_from_world,
                  subset_tree ? std::span<const Eigen::Vector3d>(subset) : cloud_mm,
                  options,
                  std::cos(options.plane_angle_deg * M_PI / 180.0)};
  std::vector<std::vector<std::pair<std::uint32_t, float>>> support(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 64),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      Scratch s;
                      for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        one_point(c, points.positions_mm[i], points.normals[i], s, e, i);
                        if (e.valid(i)) support[i] = s.support;
                      }
                    });
  e.support_begin.assign(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    e.support_begin[i] = static_cast<std::uint32_t>(e.support_point.size());
    for (const auto& [point, weight] : support[i]) {
      e.support_point.push_back(scan_index_of.empty() ? point : scan_index_of[point]);
      e.support_weight.push_back(weight);
    }
  }
  e.support_begin[n] = static_cast<std::uint32_t>(e.support_point.size());
  return e;
}

}  // namespace truecut::offline
