// Helpers for the rewrite suites: compensation matrices with one vector on
// a grid of points.
#pragma once

#include "truecut/interp/rewrite.hpp"

namespace truecut::interp::testing {

// Points every `spacing` mm over [x0, x1] x [y0, y1] at height z0, each with
// `vector`, valid, on surface 1; appended to `into` when given.
inline CompensationMatrixData plane_matrix(double x0, double x1, double y0, double y1, double z0,
                                           double spacing, const Eigen::Vector3d& vector,
                                           CompensationMatrixData into = {}) {
  for (double x = x0; x <= x1 + 1e-9; x += spacing)
    for (double y = y0; y <= y1 + 1e-9; y += spacing) {
      into.positions_mm.emplace_back(x, y, z0);
      into.vectors_mm.push_back(vector);
      into.valid.push_back(1);
      into.surface_ids.push_back(1);
    }
  return into;
}

}  // namespace truecut::interp::testing
