#include "truecut/sim/drive_surface.hpp"

#include <cmath>
#include <stdexcept>

#include "truecut/offline/ray_scene.hpp"

namespace truecut::sim {

struct DriveSurface::Impl {
  offline::RayScene nominal, adapted;
};

DriveSurface::DriveSurface(const offline::TriangleMesh& nominal,
                           const offline::TriangleMesh& adapted) {
  if (nominal.triangles.empty() || adapted.triangles.empty())
    throw std::invalid_argument("drive surface: the nominal and the adapted mesh need facets");
  impl_ = std::make_unique<Impl>(Impl{offline::RayScene(nominal), offline::RayScene(adapted)});
}

DriveSurface::~DriveSurface() = default;

double DriveSurface::offset_mm(const Eigen::Vector3d& p_mm, const Eigen::Vector3d& n) const {
  ++queries_;
  // From outside inwards: the first facet met is the surface seen from the
  // tool's side.
  offline::Ray ray;
  ray.origin_mm = p_mm + kReachMm * n;
  ray.direction = -n;
  ray.t_min_mm = 0.0;
  ray.t_max_mm = 2 * kReachMm;
  offline::RayHit nominal_hit, adapted_hit;
  impl_->nominal.intersect({&ray, 1}, {&nominal_hit, 1});
  impl_->adapted.intersect({&ray, 1}, {&adapted_hit, 1});
  // The nominal mesh lies within its faceting of p (25 µm for 2 mm facets on
  // a R20 sphere, 50 near a revolved pole); a hit farther off is another face.
  constexpr double kFacetingMm = 0.2;
  if (!nominal_hit.hit() || !adapted_hit.hit() ||
      std::abs(nominal_hit.distance_mm - kReachMm) > kFacetingMm) {
    ++misses_;
    return 0.0;
  }
  return nominal_hit.distance_mm - adapted_hit.distance_mm;
}

}  // namespace truecut::sim
