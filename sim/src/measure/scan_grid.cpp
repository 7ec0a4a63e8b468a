#include "scan_grid.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

namespace truecut::sim::measure::detail {

PoseGrid::PoseGrid(const ScanPose& pose, std::size_t pose_index, ScanMode mode, double spacing_mm,
                   double triangulation_angle_deg, const offline::TriangleMesh& mesh,
                   std::size_t max_rays)
    : mode_(mode),
      origin_(pose.position_mm),
      dir_(pose.view_dir.normalized()),
      spacing_mm_(spacing_mm),
      tan_step_(spacing_mm / pose.reference_distance_mm),
      reference_mm_(pose.reference_distance_mm),
      baseline_mm_(pose.reference_distance_mm *
                   std::tan(triangulation_angle_deg * std::numbers::pi / 180.0)) {
  const std::string where = "scan pose " + std::to_string(pose_index + 1);
  up_ = (pose.up - pose.up.dot(dir_) * dir_).normalized();
  right_ = dir_.cross(up_);

  // Extent of the mesh in grid coordinates: a = image-plane tangent (or
  // sweep position for the laser's rows), b = tangent along right.
  double row_min = std::numeric_limits<double>::infinity(), row_max = -row_min;
  double col_min = row_min, col_max = -row_min;
  for (const Eigen::Vector3d& p : mesh.vertices_mm) {
    const Eigen::Vector3d q = p - origin_;
    const double depth = q.dot(dir_);
    if (!(depth > 1e-6 * reference_mm_))
      throw std::invalid_argument(where + ": part of the mesh is behind the scanner (vertex at " +
                                  std::to_string(depth) + " mm along the view direction)");
    const double row_coord =
        mode_ == ScanMode::kFringe ? q.dot(up_) / depth / tan_step_ : q.dot(up_) / spacing_mm_;
    const double col_coord = q.dot(right_) / depth / tan_step_;
    row_min = std::min(row_min, row_coord);
    row_max = std::max(row_max, row_coord);
    col_min = std::min(col_min, col_coord);
    col_max = std::max(col_max, col_coord);
  }
  row0_ = static_cast<long>(std::floor(row_min)) - 1;
  col0_ = static_cast<long>(std::floor(col_min)) - 1;
  const double rows = std::ceil(row_max) + 1 - static_cast<double>(row0_) + 1;
  const double cols = std::ceil(col_max) + 1 - static_cast<double>(col0_) + 1;
  if (rows * cols > static_cast<double>(max_rays))
    throw std::invalid_argument(where + ": " + std::to_string(static_cast<long long>(rows)) +
                                " × " + std::to_string(static_cast<long long>(cols)) +
                                " rays exceed the limit of " + std::to_string(max_rays) +
                                " (lower the density)");
  rows_ = static_cast<std::size_t>(rows);
  cols_ = static_cast<std::size_t>(cols);
}

offline::Ray PoseGrid::ray(std::size_t row, std::size_t col) const {
  offline::Ray r;
  const double b = static_cast<double>(col0_ + static_cast<long>(col)) * tan_step_;
  const double a_index = static_cast<double>(row0_ + static_cast<long>(row));
  if (mode_ == ScanMode::kFringe) {
    r.origin_mm = origin_;
    r.direction = (dir_ + b * right_ + a_index * tan_step_ * up_).normalized();
  } else {
    r.origin_mm = origin_ + a_index * spacing_mm_ * up_;
    r.direction = (dir_ + b * right_).normalized();
  }
  return r;
}

Eigen::Vector3d PoseGrid::partner_mm(std::size_t row) const {
  if (mode_ == ScanMode::kFringe) return origin_ + baseline_mm_ * right_;
  const double a_index = static_cast<double>(row0_ + static_cast<long>(row));
  return origin_ + (a_index * spacing_mm_ + baseline_mm_) * up_;
}

double PoseGrid::local_spacing_mm(const Eigen::Vector3d& p_mm) const {
  const double depth = (p_mm - origin_).dot(dir_);
  return spacing_mm_ * std::max(1.0, depth / reference_mm_);
}

}  // namespace truecut::sim::measure::detail
