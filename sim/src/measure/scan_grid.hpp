// The ray grid of one scanner pose: rows × cols rays whose field of view is
// fitted to the mesh. Fringe: a pinhole camera, rays through a uniform grid
// on the image plane (tangent step = spacing / reference distance); laser: a
// fan along `right` (same tangent step) at every sweep position along `up`
// (step = spacing).
#pragma once

#include <Eigen/Core>

#include <cstddef>

#include "truecut/offline/mesh.hpp"
#include "truecut/offline/ray_scene.hpp"
#include "truecut/sim/measure/scanner.hpp"

namespace truecut::sim::measure::detail {

class PoseGrid {
 public:
  // Throws std::invalid_argument when part of the mesh is not in front of
  // the scanner or the grid would exceed max_rays.
  PoseGrid(const ScanPose& pose, std::size_t pose_index, ScanMode mode, double spacing_mm,
           double triangulation_angle_deg, const offline::TriangleMesh& mesh, std::size_t max_rays);

  std::size_t rows() const { return rows_; }
  std::size_t cols() const { return cols_; }
  std::size_t size() const { return rows_ * cols_; }

  offline::Ray ray(std::size_t row, std::size_t col) const;
  // The second device: the projector (fringe) or the camera (laser).
  Eigen::Vector3d partner_mm(std::size_t row) const;
  // Ray spacing on a surface facing the scanner at this point.
  double local_spacing_mm(const Eigen::Vector3d& p_mm) const;

 private:
  ScanMode mode_;
  Eigen::Vector3d origin_, dir_, right_, up_;
  double spacing_mm_, tan_step_, reference_mm_, baseline_mm_;
  long row0_ = 0, col0_ = 0;
  std::size_t rows_ = 0, cols_ = 0;
};

}  // namespace truecut::sim::measure::detail
