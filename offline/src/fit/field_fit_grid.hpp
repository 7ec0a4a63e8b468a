// Internal to the field fit: grid choice, node distances and weights.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <span>
#include <vector>

#include "truecut/offline/field_fit.hpp"

namespace truecut::offline::fit_detail {

void check_options(const FieldFitOptions& options);

// Distance (in node spacings) from each node to the nearest valid sample,
// exact up to reach_nodes; beyond it some value above reach_nodes (+inf far
// from every sample).
std::vector<float> node_distances(const rt::FieldGrid& grid, std::span<const FitSample> samples,
                                  double reach_nodes);

// Node weight from its distance (smoothstep fade), 0 on the two outermost
// node layers.
std::vector<double> node_weights(const rt::FieldGrid& grid, std::span<const float> distance_nodes,
                                 const FieldFitOptions& options);

// Trilinear cell and fractions of a position: node (i, j, k) and t in [0, 1]^3.
struct CellPosition {
  std::int32_t i = 0, j = 0, k = 0;
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
};
CellPosition cell_of(const rt::FieldGrid& grid, const Eigen::Vector3d& position_mm);

}  // namespace truecut::offline::fit_detail
