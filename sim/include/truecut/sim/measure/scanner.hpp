// The virtual optical scanner: Embree ray casts from scanner poses onto a
// machined mesh (workpiece frame, mm), with occlusion, incidence-dependent
// noise, point density in pt/mm² and an optional rigid-body registration
// error. Models and equations: docs/measurement.md.
#pragma once

#include <Eigen/Geometry>

#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "truecut/offline/mesh.hpp"

namespace truecut::sim::measure {

enum class ScanMode {
  kFringe,  // camera + projector: a grid of camera rays; a point needs both to see it
  kLaser,   // kLaser line: a fan of rays swept along a direction; the camera must see it
};

// One placement of the scanner head. The rays leave `position_mm` (fringe:
// the camera centre; laser: the laser source in the middle of its sweep)
// around `view_dir`. Fringe: the image grid spans right = view_dir × up and
// up; laser: the fan spreads along right, the head sweeps along up. The
// field of view is fitted to the mesh (every vertex in view, one spacing of
// margin).
struct ScanPose {
  Eigen::Vector3d position_mm = Eigen::Vector3d(0, 0, 300);
  Eigen::Vector3d view_dir = -Eigen::Vector3d::UnitZ();  // unit
  Eigen::Vector3d up = Eigen::Vector3d::UnitY();         // unit, ⟂ view_dir
  // Depth (along view_dir) at which a surface facing the scanner gets
  // exactly the requested density; the ray grid is angular, so nearer
  // surfaces get more points per mm², farther ones fewer (∝ 1/depth²).
  double reference_distance_mm = 300;
};

struct ScannerOptions {
  ScanMode mode = ScanMode::kFringe;
  double sigma0_mm = 0.020;          // noise σ at normal incidence; 0.005–0.050 mm
  double max_incidence_deg = 75.0;   // steeper rays give no point
  double max_sigma_factor = 3.0;     // σ(θ) = σ0·min(1/cos θ, this)
  double density_pt_per_mm2 = 25.0;  // at the reference distance, normal incidence
  // Angle between the rays and the line to the second device (projector
  // or camera) at the reference distance; sets the baseline.
  double triangulation_angle_deg = 25.0;
  std::uint64_t seed = 1;
  std::vector<ScanPose> poses;  // empty: default_scan_poses(mesh)
  // Applied to the whole cloud (and scan mesh) after measuring, x' = T·x.
  std::optional<Eigen::Isometry3d> registration_error;
  // true: normals from a plane fit to the grid neighbours (±2 cells);
  // false: the unit vector from the point towards the scanner.
  bool estimate_normals = true;
  bool build_mesh = false;  // per-pose grid triangulation
  // Longest scan-mesh edge (and neighbour distance for the normal fit) as a
  // multiple of the local ray spacing.
  double mesh_edge_factor = 4.0;
  // Refuse a pose needing more rays than this (a density or a part too large).
  std::size_t max_rays_per_pose = 40'000'000;
  // Called after each pose (pose index from 0, pose count, points so far).
  std::function<void(std::size_t, std::size_t, std::size_t)> progress;
};

struct ScanStatistics {
  std::size_t rays = 0;                // primary rays cast
  std::size_t hits = 0;                // primary rays that met the part
  std::size_t rejected_incidence = 0;  // hit beyond max_incidence_deg (either device)
  std::size_t occluded = 0;            // the second device does not see the point
  std::size_t points = 0;
  double ray_spacing_mm = 0;  // 1/√density
};

struct ScanResult {
  offline::PointCloud cloud;                 // measured points (+ normals), workpiece frame
  std::vector<std::uint32_t> pose_of_point;  // which pose measured each point
  // Unit direction of the ray each point was measured along (from the
  // scanner towards the part), before the registration error.
  std::vector<Eigen::Vector3d> ray_dirs;
  offline::TriangleMesh mesh;  // when build_mesh: vertices = cloud points
  Eigen::Isometry3d registration_error = Eigen::Isometry3d::Identity();
  std::vector<ScanPose> poses;  // the poses used
  ScanStatistics stats;
};

// Throws std::invalid_argument naming the option for an out-of-range
// setting (σ0 outside 5–50 µm, non-positive density, ...).
void validate(const ScannerOptions& options);

// Five poses around the part's bounding box: from above (+Z) and from ±X,
// ±Y, all at the same reference distance (max(300 mm, 3 × box diagonal)
// from the box centre). None from below: the part stands on its fixture.
// A face whose outward normal has its largest component anywhere but −Z
// meets one of the poses at ≤ 54.7° incidence (before occlusion).
std::vector<ScanPose> default_scan_poses(const offline::TriangleMesh& mesh);

// Deterministic: the same mesh and options give bit-identical results.
ScanResult scan(const offline::TriangleMesh& mesh, const ScannerOptions& options);

// A registration error of the given size from a seed: translation of
// `translation_mm` along a random direction, rotation by `rotation_deg`
// about a random axis through `centre_mm`.
Eigen::Isometry3d seeded_registration_error(double translation_mm, double rotation_deg,
                                            const Eigen::Vector3d& centre_mm, std::uint64_t seed);

}  // namespace truecut::sim::measure
