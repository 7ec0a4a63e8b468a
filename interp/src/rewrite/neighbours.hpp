// The compensation points that belong to a tool point: a uniform grid over
// the points and, per tool point, the (at most) 3 nearest in the metric of
// the cutting type (docs/rewrite.md, "Nearest points considering the tool").
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "truecut/interp/rewrite.hpp"

namespace truecut::interp::rewrite {

struct ToolPoint {
  Eigen::Vector3d tip_mm;
  Eigen::Vector3d axis;  // unit, tip -> spindle
};

struct Nearest {
  int count = 0;
  std::array<int, 3> index{};  // into the point set, nearest first
  Eigen::Vector3d query_mm;    // the point the blend projects (tip or ball centre)
};

class NeighbourSearch {
 public:
  // Points of `matrix` that are valid and (when `surfaces` is not empty) on
  // one of those surfaces. Throws RewriteError when none is left.
  NeighbourSearch(const CompensationMatrixData& matrix, const std::vector<std::int32_t>& surfaces,
                  CutType type, double radius_mm, double reach_mm);

  Nearest nearest(const ToolPoint& tool) const;
  // Appends the points inside the axis-aligned box [lo, hi] (and possibly
  // a few of the grid cells around it: callers test each point).
  void points_near_box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                       std::vector<int>& out) const;
  const Eigen::Vector3d& position(int i) const { return positions_[i]; }
  const Eigen::Vector3d& vector(int i) const { return vectors_[i]; }
  int size() const { return static_cast<int>(positions_.size()); }
  double reach_mm() const { return reach_mm_; }
  double radius_mm() const { return radius_mm_; }
  CutType type() const { return type_; }
  // The bounding box of the points.
  const Eigen::Vector3d& lower_mm() const { return lower_mm_; }
  const Eigen::Vector3d& upper_mm() const { return upper_mm_; }

 private:
  std::int64_t key(const Eigen::Vector3d& p) const;
  std::int64_t key(std::int64_t i, std::int64_t j, std::int64_t k) const;
  double median_spacing_mm() const;

  std::vector<Eigen::Vector3d> positions_, vectors_;
  CutType type_;
  double radius_mm_ = 0, reach_mm_ = 0, cell_mm_ = 1;
  Eigen::Vector3d origin_mm_, lower_mm_, upper_mm_;
  std::unordered_map<std::int64_t, std::vector<int>> cells_;
};

}  // namespace truecut::interp::rewrite
