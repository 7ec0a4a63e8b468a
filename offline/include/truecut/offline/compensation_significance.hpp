// Compensate only what the scan measurably shows (docs/offline.md, "Noise:
// compensate only what is measured"). A scan with 20–50 µm noise measures a
// surface that was cut within a few micrometres as a few micrometres off,
// at random; compensating that passes the noise on to the next part. So
// every compensated surface is tested first: is the error the scan shows
// on it larger than the scan's own noise can explain?
//
// Noise: from the scan itself. Each scan point's residual from its
// neighbours (the corners of the triangles it shares, or its 8 nearest
// cloud points) along the nominal normal, r = n·(p − mean of neighbours),
// has variance σ²(1 + 1/k) for independent noise σ on k neighbours; the
// noise of a surface is 1.4826 × the median of |r|/√(1 + 1/k) over the scan
// points its error vectors were measured from (robust against the few
// points on edges and steps; up to 2000 of them, evenly spread), pooled
// over all surfaces when it has too few.
//
// Test: the surface's valid error vectors are grouped into cubes of edge
// patch_mm; each cube's mean normal error m has the variance
// σ² Σ_v (W_v / n)² carried exactly from the scan points v behind it
// (ErrorVectors::support_*, W_v the sum of v's weights over the cube's n
// vectors), which counts scan points shared by neighbouring error vectors
// once. χ² = Σ m² / var over the cubes, with one degree of freedom per cube;
// the surface is compensated when χ² exceeds the χ² quantile at
// 1 − significance_level, i.e. when a surface that is exactly right would
// show this much error less often than that.
#pragma once

#include <Eigen/Geometry>

#include <cstdint>
#include <vector>

#include "truecut/offline/compensation_points.hpp"
#include "truecut/offline/error_vectors.hpp"
#include "truecut/offline/mesh.hpp"

namespace truecut::offline {

struct SignificanceOptions {
  // α: the chance of compensating a surface that is exactly right. 0: no
  // test, every surface is compensated.
  double significance_level = 1e-3;
  double patch_mm = 4.0;
  // > 0: the scanner noise σ along the normal, instead of the estimate.
  double noise_mm = 0.0;
  // A surface measured from fewer scan points takes the pooled noise.
  std::size_t min_noise_points = 30;
};

struct SurfaceSignificance {
  std::int32_t surface = 0;
  std::size_t valid_points = 0;
  std::size_t scan_points = 0;       // distinct scan points behind the valid error vectors
  double noise_mm = 0.0;             // σ used for this surface
  bool pooled_noise = false;         // σ from all surfaces (too few scan points here)
  double mean_normal_mm = 0.0;       // of the valid error vectors
  double mean_uncertainty_mm = 0.0;  // its standard deviation under the noise
  std::size_t patches = 0;
  double chi2 = 0.0;
  // max(χ² quantile at 1 − α for `patches` degrees of freedom, 2 · patches);
  // 0 when not tested.
  double threshold = 0.0;
  bool compensated = true;
};

struct SignificanceResult {
  bool tested = false;                        // false: significance_level 0, all compensated
  double pooled_noise_mm = 0.0;               // over the scan points of all surfaces
  std::size_t noise_points = 0;               // how many
  std::vector<SurfaceSignificance> surfaces;  // ascending id; surfaces with valid points
  bool compensated(std::int32_t surface) const;
};

// `scan`: the scan the error vectors were measured on (its vertices are the
// support points; triangles give the neighbours, none: a cloud), in its own
// frame, placed in the workpiece frame by world_from_scan (the registration).
// Throws std::invalid_argument for bad options or supports that do not fit.
SignificanceResult test_compensation_significance(const CompensationPoints& points,
                                                  const ErrorVectors& errors,
                                                  const TriangleMesh& scan,
                                                  const Eigen::Isometry3d& world_from_scan,
                                                  const SignificanceOptions& options = {});

// The χ² distribution's quantile (Wilson–Hilferty, within 1 % for dof ≥ 1
// at the tail probabilities used here): P(χ²_dof > q) = upper_tail.
double chi2_quantile_upper(double upper_tail, double dof);

}  // namespace truecut::offline
