// Steps of surface-mode diagnosis (surface_diagnose.cpp) that stand on their own.
#pragma once

#include <Eigen/Dense>
#include <vector>

#include "truecut/sim/measure/cmm.hpp"

namespace truecut::analysis::diagnosis {

// The noise floor of a registered residual r0 (per point of `nominal`):
// each training point (indices `tr`) paired with its nearest training
// neighbour on the same surface, σ = 1.4826 · median |r_a − r_b| / √2;
// the RMS of r0 (at least 1e-6) when there is no pair. sxy, sxx: the sums
// of r_a r_b and r_a², the neighbour correlation.
struct SurfaceNoise {
  double floor_mm = 0, sxy = 0, sxx = 0;
};
SurfaceNoise surface_noise_floor(const std::vector<sim::measure::CmmPoint>& nominal,
                                 const Eigen::VectorXd& r0, const std::vector<std::size_t>& tr);

}  // namespace truecut::analysis::diagnosis
