// Registration of a scan to the nominal model, and removal of the residual
// rigid-body motion from displacement vectors (docs/offline.md, sections
// "Registration" and "Rigid-body motion removal").
#pragma once

#include "truecut/offline/mesh.hpp"
#include "truecut/offline/rigid_transform.hpp"

#include <cstdint>
#include <span>
#include <vector>

namespace truecut::offline {

enum class RobustKernel {
  kNone,   // plain least squares
  kHuber,  // weight 1 up to k = 1.345·σ, then k/|r|: outliers count linearly
  kTukey,  // biweight, (1 − (r/c)²)² up to c = 4.685·σ, then 0: outliers ignored
};

struct IcpOptions {
  int max_iterations = 50;
  // Correspondences are taken from this many points spread evenly over the
  // nominal (datum) surface, each paired with its nearest scan point.
  std::size_t samples = 20000;
  // Samples closer than this to a sharp nominal edge (faces meeting at more
  // than sharp_edge_deg, or an open boundary) are not used: there the nearest
  // scan point may lie on the neighbouring face, and its point-to-plane
  // residual is a bias, not a misalignment.
  double edge_margin_mm = 0.5;
  double sharp_edge_deg = 30.0;
  // Pairs farther apart are not used; must exceed the initial misalignment.
  double max_correspondence_mm = 2.0;
  RobustKernel kernel = RobustKernel::kTukey;
  // σ is 1.4826 × the median |residual| of the iteration (the MAD estimate),
  // at least this much: near convergence the residuals are mostly scan
  // noise, and the floor keeps noise-sized residuals at full weight.
  double min_robust_scale_mm = 0.005;
  // Stop when an iteration moves the scan by less than both, or by less than
  // the pose's statistical noise σ/√Σw (rotation: over the RMS radius of the
  // pairs), whichever is larger.
  double converged_translation_mm = 1e-5;
  double converged_rotation_deg = 1e-5;
  // Nominal triangles that are datum surfaces (see triangles_of_surfaces);
  // empty: the whole nominal model.
  std::vector<std::uint32_t> datum_triangles;
  // Look the nearest scan point up among the previous iteration's nearest
  // few while the pose moves less than their spacing (the same point the
  // k-d tree gives, exactly; false asks the tree every time, for tests).
  bool reuse_neighbours = true;
  // Start value of the scan → workpiece transform.
  Eigen::Isometry3d initial = Eigen::Isometry3d::Identity();
  // The motion found is applied only when the scan's noise makes it unlikely
  // by chance: its Wald statistic xᵀHx/σ² (x the motion from `initial` in
  // the determined directions, H the normal matrix of the last iteration)
  // exceeds the χ² quantile of this upper tail. A scan already in place with
  // noisy datums otherwise gets a random tilt (σ = 50 µm on the implant's
  // base: 0.015°, 4.5 µm at the 17 mm shaft's top) that no fit needs. 0:
  // always apply.
  double significance_level = 0.001;
};

struct IcpResult {
  Eigen::Isometry3d scan_to_nominal = Eigen::Isometry3d::Identity();
  RigidTransformReport transform;  // of scan_to_nominal
  int iterations = 0;
  bool converged = false;
  std::size_t samples = 0;          // nominal sample points (away from edges)
  std::size_t correspondences = 0;  // pairs within max_correspondence_mm at the end
  // Point-to-plane distances of the pairs within max_correspondence_mm,
  // unweighted, at the initial and at the final transform.
  double rms_before_mm = 0.0;
  double rms_after_mm = 0.0;
  double robust_scale_mm = 0.0;  // σ of the last iteration
  // Directions of rigid motion the datum geometry determines: 6 for a generic
  // part, 3 for a plane, 5 for a cylinder. Undetermined ones are not moved.
  int determined_directions = 0;
  // The significance test (IcpOptions::significance_level): the motion's
  // Wald statistic and the χ² threshold it was held against; applied is
  // false when the motion was within the noise and the scan was left at
  // `initial` (scan_to_nominal = initial, rms_after_mm = rms_before_mm).
  double motion_chi2 = 0.0;
  double motion_threshold = 0.0;
  bool applied = true;
};

// Point-to-plane ICP: finds the rigid transform that moves the scan onto the
// nominal surface (the workpiece frame). Deterministic: the same inputs give
// bit-identical results on any number of threads. Throws std::invalid_argument
// for an empty scan or datum.
IcpResult register_scan(const TriangleMesh& nominal,
                        std::span<const Eigen::Vector3d> scan_points_mm,
                        const IcpOptions& options = {});

// Rigid-body motion removal (model-adaptation source, eqs. 3–6).
enum class RigidBodyFit {
  // Full 3-D displacement vectors (sphere method): translation = mean
  // displacement, rotation about the barycentre by least squares (SVD).
  kFullVectors,
  // Displacements known only along the nominal normals (ray method): rotation
  // and translation fitted to the normal components, about the barycentre.
  kNormalComponents,
};

struct RigidBodyMotion {
  Eigen::Vector3d barycentre_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d translation_mm = Eigen::Vector3d::Zero();
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // about the barycentre
  // x ↦ rotation·(x − barycentre) + barycentre + translation, as a transform.
  RigidTransformReport transform;
  std::size_t points_used = 0;
  int determined_directions = 0;  // as in IcpResult
  // RMS of the fitted displacement components before and after removal.
  double rms_before_mm = 0.0;
  double rms_after_mm = 0.0;

  // The rigid motion's displacement at a point.
  Eigen::Vector3d displacement_at(const Eigen::Vector3d& p_mm) const {
    return rotation * (p_mm - barycentre_mm) + barycentre_mm + translation_mm - p_mm;
  }
};

// Fits the rigid motion to the displacements of the points with use[i] != 0
// (empty `use`: all). normal_components needs one unit normal per point.
// Throws std::invalid_argument on mismatched sizes or too few points (3).
RigidBodyMotion fit_rigid_body_motion(std::span<const Eigen::Vector3d> points_mm,
                                      std::span<const Eigen::Vector3d> displacements_mm,
                                      RigidBodyFit fit, std::span<const std::uint8_t> use = {},
                                      std::span<const Eigen::Vector3d> normals = {});

// Subtracts the motion from every displacement: the whole motion for
// full_vectors, its normal component for normal_components (the vectors stay
// along their normals).
void remove_rigid_body_motion(const RigidBodyMotion& motion, RigidBodyFit fit,
                              std::span<const Eigen::Vector3d> points_mm,
                              std::span<Eigen::Vector3d> displacements_mm,
                              std::span<const Eigen::Vector3d> normals = {});

}  // namespace truecut::offline
