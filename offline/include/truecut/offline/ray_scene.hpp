// Ray casting and proximity queries against a triangle mesh. The one door to
// Embree: its types and rtcore.h stay inside offline/src/embree.
//
// Precision: Embree works in float32. The mesh is stored relative to a local
// origin (the centre of its bounding box), so vertex rounding is at most
// 2^-24 of half the box diagonal — 9 nm for a 300 mm part, wherever the part
// sits in the workpiece frame. Embree only decides which triangle a ray hits;
// distance, barycentrics and normal are then recomputed in double from that
// triangle's double vertices (RayQueryOptions::refine_in_double). The float
// stage can only matter for a ray passing within ~1e-7 of the part size of
// a triangle edge, where either neighbour gives the same hit point.
#pragma once

#include "truecut/offline/mesh.hpp"

#include <Eigen/Geometry>

#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace truecut::offline {

// Thrown for errors Embree reports through its device error callback (the
// message names the Embree error code) and for invalid input.
class RayEngineError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Ray {
  Eigen::Vector3d origin_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();  // unit length
  double t_min_mm = 0.0;                                 // search interval along the ray
  double t_max_mm = std::numeric_limits<double>::infinity();
};

struct RayHit {
  static constexpr std::uint32_t kMiss = 0xffffffffu;
  std::uint32_t triangle = kMiss;
  double distance_mm = std::numeric_limits<double>::infinity();  // along the ray
  // Hit point = (1 − u − v)·a + u·b + v·c for the triangle's corners a, b, c.
  double u = 0.0, v = 0.0;
  // Unit geometric normal, (b − a) × (c − a): it follows the triangle's winding.
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();

  bool hit() const { return triangle != kMiss; }
};

enum class RayBatch {
  kSingle,    // rtcIntersect1 per ray, blocks of rays spread over TBB threads
  kPacket16,  // rtcIntersect16 on packets of 16 consecutive rays, over TBB threads
  kStream,    // rtcIntersect1M on blocks of rays, over TBB threads
};

struct RayQueryOptions {
  // packet16 measured ~10 % faster than single and stream (docs/offline.md).
  RayBatch batch = RayBatch::kPacket16;
  // false: distance, (u, v) and normal as Embree computes them in float
  // (what the benchmark calls raw throughput).
  bool refine_in_double = true;
};

class RayScene {
 public:
  // Throws RayEngineError for an index out of range or a non-finite vertex.
  explicit RayScene(const TriangleMesh& mesh);
  ~RayScene();
  RayScene(RayScene&&) noexcept;
  RayScene& operator=(RayScene&&) noexcept;

  // hits[i] is the closest hit of rays[i] within [t_min_mm, t_max_mm].
  // Thread-safe; parallel inside.
  void intersect(std::span<const Ray> rays, std::span<RayHit> hits,
                 const RayQueryOptions& options = {}) const;

  // Places the mesh in the world frame of the queries: rays and query points
  // are given, and hits returned, in the world frame, where the mesh's
  // vertices v lie at world_from_mesh·v (default: identity). Lets a scan be
  // registered without moving its vertices or rebuilding the scene; each
  // query is moved into the mesh frame in double before it reaches Embree,
  // so the precision is that of an unmoved scene. Not thread-safe against
  // concurrent queries.
  void set_world_from_mesh(const Eigen::Isometry3d& world_from_mesh);

  // Appends, in ascending order, the triangles whose closest point to p is
  // within radius_mm (distance computed in double). Thread-safe.
  void triangles_within(const Eigen::Vector3d& p, double radius_mm,
                        std::vector<std::uint32_t>& out) const;
  // The same, with each triangle's closest point to p (world frame).
  struct NearTriangle {
    std::uint32_t triangle = 0;
    Eigen::Vector3d closest_mm = Eigen::Vector3d::Zero();
  };
  void triangles_within(const Eigen::Vector3d& p, double radius_mm,
                        std::vector<NearTriangle>& out) const;

  const Eigen::Vector3d& local_origin_mm() const;
  std::size_t triangle_count() const;
  // The vertex indices of triangle t, as in the mesh the scene was built from.
  const Triangle& triangle(std::uint32_t t) const;
  // Whether this Embree build honours ray masks (they are set either way).
  bool ray_masks_supported() const;

 private:
  // p in the mesh frame.
  template <class Found>
  void collect_within(const Eigen::Vector3d& p, double radius_mm, std::vector<Found>& out) const;

  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace truecut::offline
