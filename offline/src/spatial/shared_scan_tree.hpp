// Internal to `truecut field`: the stages that index the scan's points
// (registration, the sphere method, the significance test's noise estimate)
// share one k-d tree of them instead of building one each (about 0.1 s of
// CPU per 550k points). Each overload gives exactly what the public function
// gives; `tree` must have been built on exactly the points passed with it.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <span>

#include "spatial/kd_tree.hpp"
#include "truecut/offline/compensation_significance.hpp"
#include "truecut/offline/error_vectors.hpp"
#include "truecut/offline/registration.hpp"

namespace truecut::offline {

IcpResult register_scan(const TriangleMesh& nominal,
                        std::span<const Eigen::Vector3d> scan_points_mm, const IcpOptions& options,
                        const spatial::KdTree& scan_tree);

ErrorVectors error_vectors_by_spheres(const TriangleMesh& nominal, const CompensationPoints& points,
                                      std::span<const Eigen::Vector3d> cloud_mm,
                                      const SphereMethodOptions& options,
                                      const spatial::KdTree& cloud_tree);
// cloud_tree: of the points before world_from_tree moved them to cloud_mm
// (the scan before registration); queried through the inverse motion, so a
// registered scan needs no tree of its own.
ErrorVectors error_vectors_by_spheres(const TriangleMesh& nominal, const CompensationPoints& points,
                                      std::span<const Eigen::Vector3d> cloud_mm,
                                      const SphereMethodOptions& options,
                                      const spatial::KdTree& cloud_tree,
                                      const Eigen::Isometry3d& world_from_tree);

// scan_tree: of scan.vertices_mm (used only when the scan has no triangles).
SignificanceResult test_compensation_significance(const CompensationPoints& points,
                                                  const ErrorVectors& errors,
                                                  const TriangleMesh& scan,
                                                  const Eigen::Isometry3d& world_from_scan,
                                                  const SignificanceOptions& options,
                                                  const spatial::KdTree& scan_tree);

}  // namespace truecut::offline
