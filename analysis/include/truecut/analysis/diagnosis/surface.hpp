// Surface-mode diagnosis (issue 9, docs/diagnosis.md "Surface mode"): a
// measurement of a machined part (CMM points with deviations, or a scan) is
// compared with the same program re-machined on the believed machine
// (run_soft_cnc); the rigid registration is profiled out and reported; the
// residual is located by surface, operation and tool, and explained by the
// machine model's effects whose signatures are linearised sensitivities —
// one re-machining per parameter, nudged — selected by BIC, fitted with 95 %
// intervals, verified by re-machining the fitted model and proven on a
// held-out surface region.
#pragma once

#include <Eigen/Geometry>

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "truecut/analysis/diagnosis/diagnosis.hpp"
#include "truecut/sim/machine_description.hpp"
#include "truecut/sim/measure/cmm.hpp"

namespace truecut::analysis::diagnosis {

// The job that machined the part (as `truecut run` takes it).
struct SurfaceJob {
  std::filesystem::path program, nominal, part, tools;
  // The believed machine's file, as the user named it (messages only).
  std::filesystem::path machine_file;
  std::vector<std::filesystem::path> component_path;
  // Re-machinings go to work_dir/runs/<hash of the machine description and
  // the job's files>/ and are reused when already there (the simulation is
  // deterministic; a rebuilt simulator needs a fresh work_dir).
  std::filesystem::path work_dir;
};

struct SurfaceOptions {
  // Points whose coordinate along the nominal's longest extent lies in the
  // last `holdout_fraction` of it are held out (a surface-region split);
  // 0: none.
  double holdout_fraction = 0.3;
  double bic_threshold = 10.0;
  // Gauss–Newton iterations of the parameter fit after the linear step
  // around the believed model; each re-machines the estimate and one nudge
  // per fitted parameter. 0: the linear step only.
  int gauss_newton_iterations = 4;
  // Candidate groups to test ("tool_radius_error", "tool_length_error",
  // "rotary_location", "tool_deflection", "workpiece_deflection",
  // "squareness"); empty: all that apply (rotary_location only when the
  // program turns A or C).
  std::vector<std::string> candidates;
  std::function<void(const std::string&)> progress;
};

// A measurement brought to nominal points: per point the nominal position,
// normal, surface and the measured deviation along the normal (+ = oversize).
struct SurfaceMeasurement {
  std::string source;  // file name
  std::string kind;    // "cmm", "scan"
  std::vector<sim::measure::CmmMeasurement> points;
  // Scans only: the ICP transform applied first (scan → nominal).
  std::optional<Eigen::Isometry3d> scan_to_nominal;
  double icp_rms_before_mm = 0.0, icp_rms_after_mm = 0.0;
};

// Reads a CMM CSV as write_cmm_csv writes it (x,y,z,nx,ny,nz,surface,
// deviation_mm,valid; the deviation column is required). Throws
// DiagnosisError naming FILE:LINE.
SurfaceMeasurement read_cmm_measurement(const std::filesystem::path& file);
// A scan (STL/PLY mesh, or PLY/XYZ points): registered to the nominal by
// ICP, then the deviation at nominal points spaced `spacing_mm` apart (ray
// along the normal to a mesh; plane through the nearest points of a cloud).
SurfaceMeasurement read_scan_measurement(const std::filesystem::path& file,
                                         const offline::TriangleMesh& nominal,
                                         const std::vector<std::int32_t>& triangle_surface,
                                         double spacing_mm);

struct SurfaceRegion {
  std::string where;  // "surface", "operation", "tool"
  std::string what;   // e.g. "surface 3 (shaft +y)", "FINISH_WALLS", "T2"
  std::size_t points = 0;
  double rms_mm = 0, mean_mm = 0, max_mm = 0, ratio_to_floor = 0;
};

struct SurfaceFit {
  std::size_t points = 0;
  double rms_before_mm = 0, rms_after_mm = 0, max_before_mm = 0, max_after_mm = 0;
};

struct SurfaceDiagnosisResult {
  std::string measurement, kind, program, believed_file;
  std::size_t points = 0, valid_points = 0;
  // Registration: the ICP of a scan, and the small rigid motion profiled out
  // of every fit (translation mm, rotation µrad about the points' centroid).
  std::optional<Eigen::Isometry3d> scan_to_nominal;
  double icp_rms_before_mm = 0, icp_rms_after_mm = 0;
  Eigen::Vector3d registration_translation_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d registration_rotation_urad = Eigen::Vector3d::Zero();
  Eigen::Vector3d centroid_mm = Eigen::Vector3d::Zero();
  double noise_floor_mm = 0;
  std::vector<SurfaceRegion> mismatch;
  // Surfaces with nominal points of which none was measured ("surface 6
  // (base_bottom)"): a face the scanner never saw, or the CMM never probed.
  std::vector<std::string> unmeasured_surfaces;
  std::vector<Explanation> explanations;
  std::vector<NotIdentifiable> not_identifiable;
  std::vector<std::string> candidates_tested;
  int resimulations = 0;
  // Gauss–Newton iterations made, and whether the last step was below a
  // fifth of every parameter's standard error.
  int gauss_newton_iterations = 0;
  bool gauss_newton_converged = false;
  SurfaceFit train, heldout;
  bool has_heldout = false;
  std::string heldout_kind;  // "region: <axis> > <value> mm"
  std::string verdict;
  // Per point (for the report): nominal position, surface, residual before
  // and after, held out or not.
  std::vector<Eigen::Vector3d> position_mm;
  std::vector<int> surface;
  std::vector<double> before_mm, after_mm;
  std::vector<char> is_heldout;
  sim::MachineDescription believed, fitted;
};

// The effects surface mode can test (SurfaceOptions::candidates).
const std::vector<std::string>& surface_candidate_effects();

// Throws DiagnosisError before any re-machining for a candidate that is not
// a surface-mode effect or a measurement with fewer than 20 valid points;
// the folders it created under job.work_dir are removed again when it
// fails. A program that leaves the machine's travel, or a tool table that
// does not read, is a DiagnosisError naming job.machine_file.
SurfaceDiagnosisResult diagnose_surface(const SurfaceMeasurement& measurement,
                                        const SurfaceJob& job,
                                        const sim::MachineDescription& believed,
                                        const SurfaceOptions& options);

std::string surface_diagnosis_json(const SurfaceDiagnosisResult& result);
std::string surface_diagnosis_html(const SurfaceDiagnosisResult& result);
std::string surface_diagnosis_summary(const SurfaceDiagnosisResult& result);

}  // namespace truecut::analysis::diagnosis
