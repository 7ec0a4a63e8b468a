// Error vectors: at each compensation point, how far and in which direction
// the measured surface lies from the nominal one (measured − nominal, mm,
// workpiece frame). Two methods (docs/offline.md, "Error vectors"):
//   - rays (optical-compensation source): along the nominal normal, both
//     directions, to the scanned mesh;
//   - spheres (model-adaptation source): plane fits to the cloud points
//     within a sphere around the point, for scans without faces.
// The scan must already be registered (register_scan, transform_points).
#pragma once

#include "truecut/offline/compensation_points.hpp"
#include "truecut/offline/mesh.hpp"
#include "truecut/offline/ray_scene.hpp"

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

namespace truecut::offline {

enum class ErrorStatus : std::uint8_t {
  kValid,
  // ray method
  kNoHit,        // no scanned surface within max_distance_mm either way
  kGrazing,      // the ray meets the scanned surface at more than grazing_angle_deg
  kBackFace,     // the nearest scanned surface faces the other way (a wall's far side)
  kNominalEdge,  // the point lies on or near a sharp nominal edge or corner
  // sphere method
  kTooFewPoints,       // < min_points in the sphere, or on a plane through the point
  kIllConditioned,     // the fitted planes through the point are (nearly) parallel
  kBeyondSphereReach,  // |error| > max_displacement_ratio · Rs
  kPlaneTilted,        // a plane fitted through the point is tilted by more than
                       // plane_angle_deg from its nominal face: too few or mixed points
};
std::string_view to_string(ErrorStatus status);

// Which planes met at the point (sphere method).
enum class SphereCase : std::uint8_t { kNone, kSurface, kEdge, kCorner, kMulti };
std::string_view to_string(SphereCase c);

struct ErrorVectors {
  std::vector<Eigen::Vector3d> vectors_mm;  // zero where not valid
  std::vector<ErrorStatus> status;
  // Component along the nominal normal (the ray method's signed distance).
  std::vector<double> normal_mm;
  // Sphere method only (else empty): the case and the cloud points inside
  // the sphere (points per mm² ≈ count / (π Rs²) on a flat surface).
  std::vector<SphereCase> sphere_case;
  std::vector<std::uint32_t> points_in_sphere;  // of the points used (see scan_fraction)
  // Sphere method: the fraction of the scan's points the fits used (1: all;
  // less when SphereMethodOptions::max_points_per_sphere thinned the scan).
  double scan_fraction = 1.0;
  // Sphere method: the fraction of the nominal's facets that were clustered
  // into the planes not through the point (1: all; less when
  // SphereMethodOptions::max_facets_per_sphere thinned them).
  double nominal_fraction = 1.0;
  // The median number of facets in a sphere (0 when not counted: no bound).
  std::size_t median_facets_per_sphere = 0;
  // The scan points each valid vector was measured from: normal_mm[i]
  // changes by Σ support_weight[k] · δ_k when scan point support_point[k]
  // moves by δ_k along the normal, k in [support_begin[i],
  // support_begin[i + 1]). Ray method: the corners of the hit triangle with
  // their barycentric weights; sphere method: the points of the planes
  // fitted through the point. Nothing for an invalid point. It carries the
  // scan's noise into the uncertainty of means of error vectors
  // (compensation_significance.hpp).
  std::vector<std::uint32_t> support_begin;  // size() + 1 entries
  std::vector<std::uint32_t> support_point;  // scan vertex (ray) or cloud point (sphere)
  std::vector<float> support_weight;

  std::size_t size() const { return vectors_mm.size(); }
  bool valid(std::size_t i) const { return status[i] == ErrorStatus::kValid; }
  // One byte per point, 1 where valid (for fit_rigid_body_motion).
  std::vector<std::uint8_t> valid_mask() const;
};

struct RayMethodOptions {
  double max_distance_mm = 1.0;  // search distance along the normal, each way
  // Angle between the ray and the scanned surface's normal above which the
  // hit is grazing: the distance along the ray then exaggerates the surface
  // deviation by 1/cos, and a small registration error moves it a lot.
  double grazing_angle_deg = 60.0;
  // Nominal edges whose faces meet at more than this angle are sharp, as are
  // boundary and non-manifold edges.
  double sharp_edge_deg = 30.0;
  // Points closer than this to a sharp nominal edge are invalid: the normal
  // is undefined on the edge and the ray near it may hit the neighbouring
  // face of the scan. A vertex on a sharp edge is always invalid.
  double edge_exclusion_mm = 0.5;
  bool reject_back_faces = true;
  RayBatch batch = RayBatch::kPacket16;
};

// `scan` is the scanned mesh (registered).
ErrorVectors error_vectors_by_rays(const TriangleMesh& nominal, const CompensationPoints& points,
                                   const RayScene& scan, const RayMethodOptions& options = {});

struct SphereMethodOptions {
  double radius_mm = 1.5;  // Rs
  // In the sphere (the source's limit) and, stricter than the source, on
  // each plane through the point: a plane tilted by noise through 3 or 4
  // points moves an edge or corner far.
  std::size_t min_points = 5;
  // Nominal triangles near the point form one plane when their normals are
  // within this angle (and their planes within 0.25·Rs of each other).
  double plane_angle_deg = 30.0;
  // The source's reach limit: d ≤ 0.7·Rs.
  double max_displacement_ratio = 0.7;
  // true (this project's default): each plane is fitted to its points with
  // its own orientation (a total least-squares plane). false (the source):
  // the plane keeps the nominal orientation and only its offset along the
  // normal is fitted (the mean distance of its points).
  bool tilted_planes = true;
  // This project's bound on the cost of a fit (0: every point, the
  // source): when the median sphere holds more scan points than this, the
  // fits use a fixed pseudo-random subset of the scan (each point kept or
  // not by a hash of its index, the same subset on any thread count) of
  // about this many points per sphere. Without it the cost grows with
  // points × points per sphere: n² when the same part is scanned denser.
  // 256 points leave σ/16 of noise on a plane's offset.
  std::size_t max_points_per_sphere = 256;
  // This project's bound on the nominal's facets per sphere (0: every
  // facet, the source): when the median sphere holds more facets than this,
  // the planes through the point still come from every facet touching it,
  // the other planes near it from a fixed subset of the facets (each kept or
  // not by a hash of its index) of about this many per sphere. Without it
  // the cost grows with points × facets per sphere: n² when the same part is
  // tessellated finer.
  std::size_t max_facets_per_sphere = 64;
};

// The source's density requirement (points per mm²); reported, not enforced.
inline constexpr double kRecommendedDensityPerMm2 = 20.0;

// `cloud_mm` is the scan's points (registered).
ErrorVectors error_vectors_by_spheres(const TriangleMesh& nominal, const CompensationPoints& points,
                                      std::span<const Eigen::Vector3d> cloud_mm,
                                      const SphereMethodOptions& options = {});

struct ErrorVectorSummary {
  std::size_t points = 0;
  std::size_t valid = 0;
  std::size_t by_status[9] = {};  // indexed by ErrorStatus
  std::size_t by_case[5] = {};    // indexed by SphereCase (sphere method)
  // Over the valid vectors: mean and RMS of the normal component, RMS and
  // max of the length.
  double mean_normal_mm = 0.0;
  double rms_normal_mm = 0.0;
  double rms_length_mm = 0.0;
  double max_length_mm = 0.0;
  // Sphere method: median of count / (π Rs²) over all points, and how many
  // points fall below kRecommendedDensityPerMm2.
  double median_density_per_mm2 = 0.0;
  std::size_t below_recommended_density = 0;
};

// radius_mm: the sphere radius used (ignored for the ray method).
ErrorVectorSummary summarize(const ErrorVectors& errors, double radius_mm = 0.0);

}  // namespace truecut::offline
