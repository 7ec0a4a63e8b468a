// Refusing a scan that does not belong to the nominal (docs/offline.md,
// "Wrong scans"): one far from the workpiece frame although declared in it,
// one that registration can fit only by a large motion, one of another part,
// one whose points lie mostly off the nominal.
#pragma once

#include <cstddef>
#include <span>
#include <stdexcept>

#include <Eigen/Geometry>

#include "truecut/offline/mesh.hpp"
#include "truecut/offline/rigid_transform.hpp"

namespace truecut::offline {

struct ScanCheckOptions {
  bool enabled = true;
  // The largest displacement, anywhere on the nominal's bounding box, of the
  // rigid motion that takes the scan onto the nominal: the motion the
  // registration applied, or (scan declared in the workpiece frame) the one
  // it would apply. Also the distance beyond which a scan point is off the
  // nominal.
  double max_offset_mm = 0.3;
  // Refused when more of the scan's points than this lie off the nominal.
  double max_off_percent = 20.0;
  // The scan's points are checked at an even stride, at most this many.
  std::size_t sample_points = 20000;
};

struct ScanCheck {
  bool declared_in_frame = false;  // --no-register: the motion was found, not applied
  RigidTransformReport motion;     // scan → nominal, as found
  double motion_max_displacement_mm = 0.0;
  std::size_t points_checked = 0;
  std::size_t points_off = 0;  // farther than max_offset_mm from the nominal
  double off_percent = 0.0;
  // Median distance to the nominal of the points off it (of at most 255 of
  // them, evenly chosen; searched up to 100 mm, farther counts as 100 mm).
  double off_median_distance_mm = 0.0;
};

// What check_scan refuses; the message says how far off the scan is and
// which option (by its command-line name) accepts it.
class ScanMismatchError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The largest |T·p − p| over the corners of the mesh's bounding box, which
// bounds it over the whole mesh (|T·p − p| is convex in p).
double max_displacement_on_mesh_mm(const TriangleMesh& mesh, const Eigen::Isometry3d& t);

// Measures the scan against the nominal once scan_to_nominal is known (the
// registration's result, or identity) and throws ScanMismatchError when
// the motion or the off-nominal share exceeds the options. `motion` is the
// rigid motion the registration found (applied or, when declared_in_frame,
// only found).
ScanCheck check_scan(const TriangleMesh& nominal, std::span<const Eigen::Vector3d> scan_points_mm,
                     const Eigen::Isometry3d& scan_to_nominal, const Eigen::Isometry3d& motion,
                     bool declared_in_frame, const ScanCheckOptions& options);

}  // namespace truecut::offline
