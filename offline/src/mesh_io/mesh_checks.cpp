#include "mesh_io/mesh_checks.hpp"

#include "mesh_io/number_text.hpp"
#include "truecut/offline/mesh_io_error.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace truecut::offline::mesh_io {

std::string format_point(const Eigen::Vector3d& p) {
  std::string s = "(";
  append_double(s, p.x());
  s += ", ";
  append_double(s, p.y());
  s += ", ";
  append_double(s, p.z());
  return s + ")";
}

void check_finite(const std::vector<Eigen::Vector3d>& points,
                  const std::vector<Eigen::Vector3d>& normals, const std::filesystem::path& file,
                  std::string_view word) {
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!all_finite(points[i])) {
      throw MeshIoError(file, std::string(word) + " " + std::to_string(i) +
                                  " has a non-finite coordinate " + format_point(points[i]));
    }
  }
  for (std::size_t i = 0; i < normals.size(); ++i) {
    if (!all_finite(normals[i])) {
      throw MeshIoError(file, std::string(word) + " " + std::to_string(i) +
                                  " has a non-finite normal " + format_point(normals[i]));
    }
  }
}

bool is_degenerate(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                   double tolerance) {
  const Eigen::Vector3d ab = b - a, ac = c - a, bc = c - b;
  const double longest_sq = std::max({ab.squaredNorm(), ac.squaredNorm(), bc.squaredNorm()});
  return ab.cross(ac).norm() <= tolerance * longest_sq;
}

void handle_degenerate_triangles(std::vector<Triangle>& triangles,
                                 std::vector<std::uint32_t>& source_face,
                                 const std::vector<Eigen::Vector3d>& vertices,
                                 const MeshReadOptions& options, const std::filesystem::path& file,
                                 std::string_view word, MeshReadReport& report) {
  const bool mapped = !source_face.empty();
  auto face_of = [&](std::size_t i) { return mapped ? std::size_t{source_face[i]} : i; };
  // Before the area test: a corner at 1e39 mm makes any facet look like a
  // sliver, and the message would blame its shape instead of its size.
  for (std::size_t i = 0; i < triangles.size(); ++i) {
    for (int corner = 0; corner < 3; ++corner) {
      const Eigen::Vector3d& p = vertices[triangles[i][corner]];
      if (p.cwiseAbs().maxCoeff() <= kMaxCoordinateMm) continue;
      std::string msg = std::string(word) + " " + std::to_string(face_of(i)) + " corner " +
                        std::to_string(corner) + " " + format_point(p) + " is outside ±";
      append_double(msg, kMaxCoordinateMm);
      msg += " mm (no part is larger than 1 km; check the unit)";
      throw MeshIoError(file, msg);
    }
  }
  std::size_t kept = 0;
  for (std::size_t i = 0; i < triangles.size(); ++i) {
    const Triangle& t = triangles[i];
    if (!is_degenerate(vertices[t[0]], vertices[t[1]], vertices[t[2]],
                       options.degenerate_tolerance)) {
      triangles[kept] = t;
      if (mapped) source_face[kept] = source_face[i];
      ++kept;
      continue;
    }
    const std::size_t face = face_of(i);
    const Eigen::Vector3d &a = vertices[t[0]], &b = vertices[t[1]], &c = vertices[t[2]];
    const double area_mm2 = 0.5 * (b - a).cross(c - a).norm();
    const double longest_mm =
        std::sqrt(std::max({(b - a).squaredNorm(), (c - a).squaredNorm(), (c - b).squaredNorm()}));
    if (options.degenerate_faces == DegenerateFaces::kDrop) {
      report.dropped_triangles.push_back({i, face, area_mm2, longest_mm});
      continue;
    }
    std::size_t first = i, last = i;  // the face's triangles are consecutive
    while (first > 0 && face_of(first - 1) == face) {
      --first;
    }
    while (last + 1 < triangles.size() && face_of(last + 1) == face) {
      ++last;
    }
    std::string msg = std::string(word) + " " + std::to_string(face);
    if (last > first) {
      msg += " (fan triangle " + std::to_string(i - first) + " of " +
             std::to_string(last - first + 1) + ")";
    }
    msg += " is degenerate (zero area: ";
    append_double(msg, area_mm2);
    msg += " mm² for a longest edge of ";
    append_double(msg, longest_mm);
    msg += " mm; vertices " + std::to_string(t[0]) + " " + format_point(vertices[t[0]]) + ", " +
           std::to_string(t[1]) + " " + format_point(vertices[t[1]]) + ", " + std::to_string(t[2]) +
           " " + format_point(vertices[t[2]]) + ")";
    throw MeshIoError(file, msg);
  }
  report.degenerate_triangles_dropped = triangles.size() - kept;
  triangles.resize(kept);
  if (mapped) source_face.resize(kept);
}

void check_writable(const TriangleMesh& mesh, const std::filesystem::path& file) {
  if (!mesh.normals.empty() && mesh.normals.size() != mesh.vertices_mm.size()) {
    throw MeshIoError(file, "the mesh has " + std::to_string(mesh.normals.size()) +
                                " normals for " + std::to_string(mesh.vertices_mm.size()) +
                                " vertices");
  }
  const std::size_t n = mesh.vertices_mm.size();
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    for (std::uint32_t v : mesh.triangles[i]) {
      if (v >= n) {
        throw MeshIoError(file, "triangle " + std::to_string(i) + " refers to vertex " +
                                    std::to_string(v) + ", but the mesh has " + std::to_string(n) +
                                    " vertices");
      }
    }
  }
}

void check_writable_vertex(const Eigen::Vector3d& p, std::size_t index,
                           const std::filesystem::path& file, std::string_view word) {
  if (!all_finite(p)) {
    throw MeshIoError(file, "cannot write " + std::string(word) + " " + std::to_string(index) +
                                ": non-finite coordinate " + format_point(p));
  }
}

void check_writable_normal(const Eigen::Vector3d& n, std::size_t index,
                           const std::filesystem::path& file) {
  if (!all_finite(n)) {
    throw MeshIoError(file, "cannot write the normal of vertex " + std::to_string(index) +
                                ": non-finite " + format_point(n));
  }
}

}  // namespace truecut::offline::mesh_io
