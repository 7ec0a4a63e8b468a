// What the scanner derives from the measured grid of one pose: normals from
// a plane fit to grid neighbours and the grid triangulation of the scan mesh.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <vector>

#include "truecut/offline/mesh.hpp"

namespace truecut::sim::measure::detail {

// The measured points of one pose on its rows × cols ray grid.
struct MeasuredGrid {
  std::size_t rows = 0, cols = 0;
  std::vector<std::int32_t> point;  // rows·cols, index into the cloud or −1
  // Longest accepted distance between grid neighbours one cell apart, as a
  // function of a point (edge factor × local ray spacing).
  std::function<double(const Eigen::Vector3d&)> edge_limit_mm;
};

// Unit normal of every point of the grid, written into normals[point]: the
// least-squares plane through the neighbours within ±2 cells that are no
// farther than (cells apart) × edge limit, oriented towards the scanner
// (−ray direction); the view direction itself with fewer than 5 neighbours.
void estimate_grid_normals(const MeasuredGrid& grid, const std::vector<Eigen::Vector3d>& points_mm,
                           const std::vector<Eigen::Vector3d>& ray_dirs,
                           std::vector<Eigen::Vector3d>& normals);

// Two triangles per grid cell with four points (split along the shorter
// diagonal), one with three; a triangle is kept when every edge is within
// the edge limit. Winding faces the scanner. Appended to `triangles`.
void triangulate_grid(const MeasuredGrid& grid, const std::vector<Eigen::Vector3d>& points_mm,
                      const std::vector<Eigen::Vector3d>& ray_dirs,
                      std::vector<offline::Triangle>& triangles);

}  // namespace truecut::sim::measure::detail
