// Smoothing of a compensation matrix before the blend (--smooth): a matrix
// of raw scan points carries the scanner's noise into the part (the
// optical-compensation source measured it, and named smoothing as the
// remedy); the correction field is smoothed by its fit, a matrix is not.
#pragma once

#include "truecut/interp/rewrite_matrix.hpp"

namespace truecut::interp::rewrite {

// Every valid vector replaced by the Gaussian-weighted mean (sigma = radius
// / 2, cut off at the radius) of the valid vectors of the same surface id
// within `radius_mm` of its point, itself included. Positions, validity and
// surface ids are kept; radius 0 returns the matrix unchanged.
CompensationMatrixData smooth_matrix(const CompensationMatrixData& matrix, double radius_mm);

}  // namespace truecut::interp::rewrite
