// The surface a part's program is generated for when it is not the nominal:
// the adapted geometry `truecut field` writes (adapted.stl: the nominal mesh
// with every compensated vertex moved by the smoothed compensation). The
// model-adaptation source (Sortino et al.) regenerates the tool path from
// that model; this is the project's path generator driven by it
// (docs/parts.md, "Programs driven by the adapted geometry").
#pragma once

#include <Eigen/Core>

#include <atomic>
#include <cstddef>
#include <memory>

#include "truecut/offline/mesh.hpp"

namespace truecut::sim {

class DriveSurface {
 public:
  // Both meshes in the workpiece frame. Throws std::invalid_argument when
  // either is empty.
  DriveSurface(const offline::TriangleMesh& nominal, const offline::TriangleMesh& adapted);
  ~DriveSurface();
  DriveSurface(const DriveSurface&) = delete;
  DriveSurface& operator=(const DriveSurface&) = delete;

  // How far the adapted surface lies outside the nominal mesh (mm, + = more
  // material) at the nominal surface point p_mm along its outward unit
  // normal n: both meshes are cut by the same line p + t·n, |t| <= 0.5 mm,
  // so the nominal's faceting cancels. 0, and counted as a miss, where either
  // mesh has no facet on that line within reach.
  double offset_mm(const Eigen::Vector3d& p_mm, const Eigen::Vector3d& n) const;

  std::size_t queries() const { return queries_; }
  std::size_t misses() const { return misses_; }

  static constexpr double kReachMm = 0.5;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  mutable std::atomic<std::size_t> queries_{0}, misses_{0};
};

}  // namespace truecut::sim
