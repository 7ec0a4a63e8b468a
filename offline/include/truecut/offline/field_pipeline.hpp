// The whole offline chain of `truecut field` (docs/offline.md, "truecut
// field"): registration → compensation points → error vectors → (optional
// rigid-body motion removal) → mirror → truss smoothing → adapted mesh →
// tool path → tool-centre placement → field fit, with statistics and the
// time of every stage. Files are read and written by the caller
// (field_outputs.hpp writes the results).
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "truecut/interp/canon.hpp"
#include "truecut/offline/compensation_matrix.hpp"
#include "truecut/offline/compensation_significance.hpp"
#include "truecut/offline/error_vectors.hpp"
#include "truecut/offline/field_fit.hpp"
#include "truecut/offline/mesh.hpp"
#include "truecut/offline/registration.hpp"
#include "truecut/offline/scan_check.hpp"
#include "truecut/offline/tool_centre_placement.hpp"
#include "truecut/offline/tool_path.hpp"
#include "truecut/offline/tool_rotation.hpp"
#include "truecut/offline/truss_smoothing.hpp"

namespace truecut::offline {

enum class ErrorMethod { kRay, kSphere };

struct FieldPipelineOptions {
  ErrorMethod method = ErrorMethod::kRay;
  // 0: the compensation points are the nominal vertices of the compensated
  // surfaces; > 0: an even sampling of them at this spacing.
  double spacing_mm = 0.0;
  std::vector<std::int32_t> surfaces;        // compensated surfaces; empty: all
  std::vector<std::int32_t> datum_surfaces;  // registration datum; empty: the whole nominal
  bool register_scan = true;                 // false: the scan is already in the workpiece frame
  bool remove_rigid_body_motion = false;  // after the error vectors (model-adaptation eqs. 3–6)
  IcpOptions icp;
  ScanCheckOptions scan_check;  // refuse scans that do not belong to the nominal
  RayMethodOptions ray;
  SphereMethodOptions sphere;
  // Which surfaces the scan shows measurably wrong; the others get no
  // compensation (compensation_significance.hpp).
  SignificanceOptions significance;
  TrussOptions truss;
  // The truss is a Tikhonov smoother: the weight that balances bias against
  // noise grows with the noise's variance. kb/kc is chosen for a scanner of
  // this noise (the demo's 20 µm) and scaled by (σ / this)² when the scan is
  // noisier (σ the significance test's estimate from the scan itself); never
  // below kb_over_kc. 0: kb/kc as given.
  double truss_reference_noise_mm = 0.02;
  FieldFitOptions fit;  // fit.spacing_mm is the field resolution
  ToolPathOptions path;
  PlacementOptions placement;
  // Fit a rotation of the tool too (tool_rotation.hpp): the field gets the
  // channels rx ry rz. false: translation only, the field as before.
  bool tool_rotation = false;
  ToolRotationOptions rotation;
  // Budgets, checked before any work: refused (std::invalid_argument naming
  // the command-line option) when the compensation points that spacing_mm
  // would place (about the compensated area / spacing²), or the field grid
  // per layer that fit.spacing_mm would need over the part (its extent plus
  // the largest tool radius), exceed them.
  double max_compensation_points = 20e6;
  double max_grid_nodes = double(std::int64_t{1} << 24);
  // And the memory the run would take, estimated from what decides it: the
  // compensation points (each with its placements, fit samples and, for the
  // sphere method, its support list of scan points), the scan and the field
  // grid; refused above this many MB (--max-memory-mb).
  double max_memory_mb = 4096;
  // Run the scan chain (registration, error vectors, truss) and the program
  // chain (tool path, placement) concurrently; false: one after the other
  // (per-stage CPU times in the benchmark). The results are the same.
  bool concurrent_stages = true;
};

struct FieldPipelineInputs {
  const TriangleMesh* nominal = nullptr;
  // One surface id per nominal triangle; empty: segment_surfaces(nominal).
  std::vector<std::int32_t> triangle_surface_ids;
  // The scan: a mesh for the ray method, its vertices are the cloud for the
  // sphere method.
  const TriangleMesh* scan = nullptr;
  // Optional: the surface the program leaves on an error-free machine (the
  // as-programmed cut — scallops, cusps, chordal facets — e.g. `truecut run`
  // on the ideal machine), in the workpiece frame. The error vectors are then
  // measured against it instead of the nominal: the scan minus the expected
  // cut along the same ray is the machine's error alone, and what the program
  // itself leaves (a ball's 42 µm scallops at 1 mm stepover) is not
  // compensated — a correction placed at the tool centre cannot remove it,
  // and sampled at the compensation points it only aliases into the field.
  // Its error vectors use the ray method with the same options; a point
  // where it gives none is invalid.
  const TriangleMesh* expected = nullptr;
  const interp::CanonProgram* program = nullptr;
  std::vector<ToolShape> tools;
  // A further iteration: the field in use when the scanned part was cut.
  // The new field is that field plus the new compensation (each fit sample
  // gets base(tool, tcp) added), so the residual error of a compensated part
  // refines the correction instead of replacing it.
  const rt::CorrectionField* base_field = nullptr;
  // Its file, for messages. A base field without a layer for any tool the
  // program cuts with (before any work), without one for a tool whose passes
  // carry compensation, or adding nothing at the tool centres that cut the
  // compensated surfaces (at the fit) is std::invalid_argument: a base
  // dropped without a word cut the next part with the new increment alone.
  std::string base_field_name = "the base field";
};

// Statistics of a set of vectors (error or compensation), over the valid ones.
struct VectorStatistics {
  std::size_t points = 0;
  std::size_t valid = 0;
  double percent_invalid = 0.0;
  Eigen::Vector3d mean_mm = Eigen::Vector3d::Zero();  // mean vector
  double mean_length_mm = 0.0;
  double rms_length_mm = 0.0;
  double max_length_mm = 0.0;
  double mean_normal_mm = 0.0;  // component along the nominal normal
  double rms_normal_mm = 0.0;
};
VectorStatistics vector_statistics(std::span<const Eigen::Vector3d> vectors_mm,
                                   std::span<const std::uint8_t> valid,
                                   std::span<const Eigen::Vector3d> normals);

struct StageTime {
  std::string name;
  double wall_s = 0.0;
  // The process's peak resident memory when the stage ended (getrusage
  // ru_maxrss): the high-water mark so far, not the stage's own use.
  double peak_rss_mb = 0.0;
};

struct FieldPipelineResult {
  std::vector<std::int32_t> triangle_surface_ids;
  std::optional<IcpResult> registration;
  std::optional<ScanCheck> scan_check;
  // What the registration took out of the measurement: the largest
  // displacement of the motion it applied, anywhere on the nominal. Without
  // datum surfaces a rigid part of the machined error (one side cut 30 µm
  // long) is fitted away with the misplacement; absorbed_beyond_noise says
  // the motion, applied because the noise cannot explain it, exceeds σ of
  // the scan's noise, all faces being the datum.
  double registration_max_displacement_mm = 0.0;
  bool registration_absorbed_beyond_noise = false;
  std::optional<RigidBodyMotion> rigid_body_motion;
  CompensationPoints points;
  ErrorVectors errors;
  ErrorVectorSummary error_summary;
  CompensationMatrix matrix;        // mirror of the raw error vectors
  SignificanceResult significance;  // per surface: compensated or within the noise
  // Per nominal vertex: the truss-smoothed compensation (zero off the
  // compensated surfaces) and the adapted mesh (nominal + that).
  TrussResult truss;
  double truss_kb_over_kc = 0.0;                 // the kb/kc used (truss_reference_noise_mm)
  std::vector<std::uint8_t> vertex_compensated;  // 1 where the adapted mesh moved the vertex
  TriangleMesh adapted;
  // The vectors the field is fitted to, one per compensation point: the
  // truss-smoothed vertex vectors (vertex points) or the raw mirror (sampled
  // points, smoothed by the fit's regularisation); zero on surfaces whose
  // measured error is within the scan's noise.
  std::vector<Eigen::Vector3d> field_vectors_mm;
  // The compensation matrix's vectors (dx,dy,dz of compensation_matrix.csv,
  // what the rewriter reads), one per compensation point: where a tool cuts
  // the point, the mean of the field's correction at the tool centres that
  // cut it (what the component applies there); elsewhere the truss-smoothed
  // vertex compensation at the point (interpolated in its triangle at a
  // sampled point); zero where the point is invalid or its surface's error
  // is within the scan's noise. matrix keeps the raw mirror.
  std::vector<Eigen::Vector3d> smoothed_matrix_mm;
  ToolPath path;
  PlacementResult placement;
  std::vector<ToolSamples> tool_samples;  // what the fit got, per tool
  // With a base field: the fit samples, those it added a correction to, and
  // those outside its grid.
  std::size_t base_samples = 0, base_samples_corrected = 0, base_samples_outside = 0;
  // The estimate the memory budget was checked against, MB.
  double estimated_memory_mb = 0.0;
  std::optional<FieldFitResult> fit;  // set when the pipeline returns
  // With tool_rotation: over all tools, the estimate's counts
  // (tool_rotation.hpp): samples given a rotation, samples whose rotation
  // the machine could not give in full, and the most left out of one, rad.
  std::int64_t rotation_tilted_samples = 0;
  std::int64_t rotation_insignificant_samples = 0;  // slope within the noise: left to the fit
  std::int64_t rotation_cut_samples = 0;
  double rotation_max_left_out_rad = 0.0;
  VectorStatistics error_statistics;         // raw error vectors
  VectorStatistics compensation_statistics;  // field_vectors_mm over the valid points
  // Largest correction the outputs apply: over the field samples and the
  // adapted mesh's vertex moves.
  double max_correction_mm = 0.0;
  double max_vertex_move_mm = 0.0;  // of the adapted mesh
  // Wall time of every stage from its own start (stages of the two chains
  // overlap, see FieldPipelineOptions::concurrent_stages), in pipeline order.
  std::vector<StageTime> stages;
  double total_wall_s = 0.0;
};

// Called after every stage with its name, its wall time and a short detail.
using PipelineProgress =
    std::function<void(const std::string& stage, double wall_s, const std::string& detail)>;

// Throws std::invalid_argument for inconsistent inputs (missing pointers,
// a scan without faces for the ray method, no valid compensation point cut
// by any tool, ...) and whatever the stages throw.
FieldPipelineResult run_field_pipeline(const FieldPipelineInputs& inputs,
                                       const FieldPipelineOptions& options,
                                       const PipelineProgress& progress = {});

}  // namespace truecut::offline
