// Regularised least-squares fit of a CorrectionField (rt/) to scattered
// compensation vectors, one layer per tool.
//
// The caller's responsibility: every sample's position_mm must already be
// the tool-centre point (TCP = programmed point = tool tip) of that tool when
// it cuts the measured point, in the workpiece frame
// (tool_centre_placement.hpp finds it from the program). The field is looked
// up by the controller at the TCP; this fit does not move anything.
//
// Grid: one for all tools, axis-aligned, spacing_mm on every axis, covering
// the valid samples' bounding box plus a margin of
//   (support_radius_nodes + fade_nodes + 2) · spacing_mm
// so the weighted region and the two zero outer node layers fit inside.
//
// Method multilevel_bspline (the default; docs/offline.md, "Field fit"):
// per tool, an affine part fitted by least squares (gradient only along
// directions in which the samples spread by >= one spacing), then cubic
// B-spline control lattices of spacing 2^l · spacing_mm aligned with the
// grid, coarse to fine, each fitted to the residual of the previous ones with
// the closed-form local weights of Lee, Wolberg & Shin (1997), then
// refinement_iterations more passes on the finest lattice; the control
// values of the finest lattice are damped by the ridge
// smoothness × (mean Σ w² of the control points with data). The node values
// are the affine part plus all lattices evaluated at the nodes: the same C2
// function the tricubic evaluator interpolates from them. O(samples), no
// linear system; membrane_weight is not used.
//
// Method least_squares: node vectors N (per component, per tool) minimise
//
//   Σ_p |T(p) N − v_p|²  +  λ ρ Σ_nodes Σ_axes |Δ²_axis N|²  +  μ ρ Σ_far edges |Δ N|²
//
// T(p) the trilinear weights of the 8 nodes around sample p, Δ² the second
// difference (in node units) along x, y and z, Δ the first difference along a
// grid edge between two nodes both farther than the support radius from the
// data, ρ = valid samples / nodes within the support radius (so λ does not
// depend on the sampling density). The membrane term μ = membrane_weight
// acts only off the data: it makes the system definite there (Δ² alone
// leaves linear extrapolation free) and extends the field roughly constantly
// into the fade, without biasing a linear field where it was measured.
// Because the field is evaluated with the interpolating tricubic B-spline,
// not trilinearly, the fit is then refined: `refinement_iterations` times the
// residual of the actual evaluator at the samples is fitted again with the
// same factorised system and added.
//
// Unknowns: only nodes within (support + fade + 2) · spacing of a sample;
// the rest stay 0 (their weight is 0). Exact, but CG needs thousands of
// iterations at 1e5 unknowns (minutes at the source's scale).
//
// Weight: node weight 1 within support_radius_nodes · spacing of a valid
// sample, falling with a smoothstep of the distance to 0 over a further
// fade_nodes · spacing, and 0 on the two outermost node layers — so the
// correction joins zero C1-smoothly at the grid boundary (correction_field.hpp).
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <span>
#include <vector>

#include "truecut/rt/core/correction_field.hpp"

namespace truecut::offline {

// One compensation point, as plain data.
struct FitSample {
  Eigen::Vector3d position_mm = Eigen::Vector3d::Zero();  // tool-centre point, see above
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();      // unit nominal normal
  Eigen::Vector3d vector_mm = Eigen::Vector3d::Zero();    // compensation vector
  // true: only normal·vector_mm is measured (a ray-method error vector says
  // nothing about the tangential components); the multilevel fit weighs its
  // tangential components (taken as zero) at 2 %, so a sample that measures
  // them (a wall meeting a face) sets them. false: the whole vector counts
  // in full. The least-squares method always fits whole vectors.
  bool along_normal_only = false;
  bool valid = true;
  std::int32_t surface_id = 0;
};

struct ToolSamples {
  std::int32_t tool = 0;
  std::vector<FitSample> samples;
};

enum class FieldFitMethod {
  kMultilevelBspline,  // default: O(samples), see the top of this file
  kLeastSquares,       // the regularised system above, solved by CG
};

struct FieldFitOptions {
  FieldFitMethod method = FieldFitMethod::kMultilevelBspline;
  double spacing_mm = 1.0;
  double smoothness = 0.1;        // λ
  double membrane_weight = 1e-4;  // μ
  double support_radius_nodes = 2.5;
  double fade_nodes = 3.0;
  int refinement_iterations = 2;
};

struct FieldFitLayerStats {
  std::int32_t tool = 0;
  std::int64_t valid_samples = 0;
  std::int64_t unknown_nodes = 0;  // nodes within reach of the data (see the top)
  // |field(p) − v_p| over valid samples, final evaluator; for samples known
  // along their normal only, the normal component of the difference.
  double residual_rms_mm = 0.0;
  double residual_max_mm = 0.0;
};

struct FieldFitResult {
  rt::CorrectionField field;
  std::vector<FieldFitLayerStats> layers;  // same order as the input tools
};

// Throws std::invalid_argument: no tools, duplicate or negative tool, no
// valid sample at all, non-finite valid sample, bad options, or a grid above
// rt::CorrectionField::kMaxNodes. A tool without valid samples gets a layer
// of zeros with weight 0.
FieldFitResult fit_correction_field(std::span<const ToolSamples> tools,
                                    const FieldFitOptions& options = {});

// The grid fit_correction_field uses for these samples (exposed for tests).
rt::FieldGrid field_fit_grid(std::span<const ToolSamples> tools, const FieldFitOptions& options);

}  // namespace truecut::offline
