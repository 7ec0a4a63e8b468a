// Checks the readers and writers share: finite coordinates, index ranges,
// degenerate (zero-area) triangles.
#pragma once

#include "truecut/offline/mesh.hpp"
#include "truecut/offline/mesh_io_options.hpp"

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace truecut::offline::mesh_io {

std::string format_point(const Eigen::Vector3d& p);

inline bool all_finite(const Eigen::Vector3d& p) {
  return std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z());
}

// Throws MeshIoError "<word> <i> has a non-finite coordinate (x, y, z)" for
// the first point (and "... non-finite normal" for the first normal) that is
// not finite.
void check_finite(const std::vector<Eigen::Vector3d>& points,
                  const std::vector<Eigen::Vector3d>& normals, const std::filesystem::path& file,
                  std::string_view word);

bool is_degenerate(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                   double tolerance);

// A mesh coordinate beyond this is a unit mix-up or a corrupt file.
inline constexpr double kMaxCoordinateMm = 1e6;

// Refuses a corner outside ±kMaxCoordinateMm, naming the face; then
// applies options.degenerate_faces. source_face[i] is the index in the file of
// the face triangle i came from (empty: i itself); faces with more than one
// triangle are fan-triangulated polygons. `word` names faces in messages
// ("facet", "face"). Records what it drops in report (count and list).
void handle_degenerate_triangles(std::vector<Triangle>& triangles,
                                 std::vector<std::uint32_t>& source_face,
                                 const std::vector<Eigen::Vector3d>& vertices,
                                 const MeshReadOptions& options, const std::filesystem::path& file,
                                 std::string_view word, MeshReadReport& report);

// For writers: throws naming the triangle whose index is out of range, or the
// normals array when its size does not match.
void check_writable(const TriangleMesh& mesh, const std::filesystem::path& file);
void check_writable_vertex(const Eigen::Vector3d& p, std::size_t index,
                           const std::filesystem::path& file, std::string_view word);
void check_writable_normal(const Eigen::Vector3d& n, std::size_t index,
                           const std::filesystem::path& file);

}  // namespace truecut::offline::mesh_io
