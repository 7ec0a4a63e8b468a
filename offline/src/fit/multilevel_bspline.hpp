// Internal to the field fit: multilevel B-spline approximation (Lee, Wolberg
// & Shin 1997) of scattered vectors onto the nodes of a field grid.
#pragma once

#include <Eigen/Core>

#include <span>
#include <vector>

#include "truecut/offline/field_fit.hpp"

namespace truecut::offline::fit_detail {

// Node values (grid.node_count() entries, x fastest) of the sum of cubic
// B-spline lattices fitted coarse to fine to the residual of the previous
// ones at the valid samples. The lattices are dyadic refinements of the grid,
// so the interpolating tricubic spline of these node values (rt::CorrectionField)
// is the same function away from the grid boundary.
std::vector<Eigen::Vector3d> multilevel_bspline_nodes(const rt::FieldGrid& grid,
                                                      std::span<const FitSample> samples,
                                                      const FieldFitOptions& options);

}  // namespace truecut::offline::fit_detail
