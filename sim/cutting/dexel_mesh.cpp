// The machined surface as a mesh, and the totals of the dexel model.
#include <algorithm>
#include <vector>

#include <Eigen/Geometry>

#include "truecut/offline/ply_io.hpp"
#include "truecut/offline/stl_io.hpp"
#include "truecut/sim/cutting/dexel_model.hpp"

namespace truecut::sim::cutting {

offline::TriangleMesh DexelModel::machined_mesh() const {
  offline::TriangleMesh mesh;
  // A line holds a surface point when its height lies strictly inside
  // (floor, stock cap). Cut through to the floor, the material is gone from
  // the whole line (the neighbouring face of a convex edge went deeper); at
  // the cap, material continues beyond it (the neighbouring face of a
  // concave edge is oversize). Such a vertex p + h·n is no point of the
  // machined surface (a spike the CMM would probe): a dexel on a sharp edge
  // takes the vertex of a partner on the other face that has a surface point
  // (the corner where the machined faces meet), and from there the vertex
  // spreads to the mesh neighbours without one (a gouge or oversize wider
  // than the dexel spacing) while it lies within max_depth_mm of their line.
  const std::size_t nd = position_.size();
  auto on_line = [&](std::size_t i) {
    return height_[i] > floor_[i] && height_[i] < options_.max_stock_mm;
  };
  std::vector<Eigen::Vector3d> vertex(nd);
  std::vector<char> placed(nd, 0);
  std::vector<std::uint32_t> queue;
  for (std::size_t i = 0; i < nd; ++i) {
    vertex[i] = position_[i] + height_[i] * normal_[i];
    if (on_line(i)) {
      placed[i] = 1;
      continue;
    }
    for (std::size_t j = partner_[i]; j != i; j = partner_[j])
      if (on_line(j)) {
        vertex[i] = position_[j] + height_[j] * normal_[j];
        placed[i] = 1;
        queue.push_back(static_cast<std::uint32_t>(i));
        break;
      }
  }
  bool any_unplaced = false;
  for (std::size_t i = 0; i < nd; ++i)
    any_unplaced = any_unplaced || !placed[i];
  if (any_unplaced) {
    std::vector<std::uint32_t> start(nd + 1, 0), items(3 * 2 * triangles_.size());
    for (const auto& t : triangles_)
      for (auto v : t)
        start[v + 1] += 2;
    for (std::size_t i = 0; i < nd; ++i)
      start[i + 1] += start[i];
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (const auto& t : triangles_)
      for (int k = 0; k < 3; ++k) {
        items[fill[t[k]]++] = t[(k + 1) % 3];
        items[fill[t[k]]++] = t[(k + 2) % 3];
      }
    // Spreads placed vertices to unplaced neighbours (cut through only, or
    // any) while they lie within max_depth_mm of the neighbour's line.
    auto spread = [&](bool cut_through_only) {
      for (std::size_t q = 0; q < queue.size(); ++q) {
        const std::uint32_t from = queue[q];
        for (std::uint32_t k = start[from]; k < start[from + 1]; ++k) {
          const std::uint32_t d = items[k];
          if (placed[d] || (cut_through_only && height_[d] > floor_[d])) continue;
          const Eigen::Vector3d off = vertex[from] - position_[d];
          if ((off - off.dot(normal_[d]) * normal_[d]).norm() > options_.max_depth_mm) continue;
          vertex[d] = vertex[from];
          placed[d] = 1;
          queue.push_back(d);
        }
      }
    };
    spread(false);
    // Edge dexels cut through on both sides (a convex edge with both faces
    // below nominal) have no partner to take: they take a neighbour's vertex
    // on their own face (the edge is rounded off by one dexel spacing).
    queue.clear();
    for (std::size_t i = 0; i < nd; ++i)
      if (placed[i]) queue.push_back(static_cast<std::uint32_t>(i));
    spread(true);
  }
  mesh.vertices_mm = std::move(vertex);
  // Relocated vertices can collapse a triangle; readers reject those (STL
  // stores float), so drop the ones that are degenerate in float.
  mesh.triangles.reserve(triangles_.size());
  for (const auto& t : triangles_) {
    if (placed[t[0]] + placed[t[1]] + placed[t[2]] == 3 && on_line(t[0]) && on_line(t[1]) &&
        on_line(t[2])) {
      mesh.triangles.push_back(t);
      continue;
    }
    const Eigen::Vector3d a = mesh.vertices_mm[t[0]].cast<float>().cast<double>();
    const Eigen::Vector3d ab = mesh.vertices_mm[t[1]].cast<float>().cast<double>() - a;
    const Eigen::Vector3d ac = mesh.vertices_mm[t[2]].cast<float>().cast<double>() - a;
    const double longest_sq =
        std::max({ab.squaredNorm(), ac.squaredNorm(), (ac - ab).squaredNorm()});
    if (ab.cross(ac).norm() > 1e-9 * longest_sq) mesh.triangles.push_back(t);
  }
  const auto base = static_cast<std::uint32_t>(position_.size());
  mesh.vertices_mm.insert(mesh.vertices_mm.end(), fixed_vertices_.begin(), fixed_vertices_.end());
  for (const auto& t : fixed_triangles_)
    mesh.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  return mesh;
}

void DexelModel::write_machined(const std::filesystem::path& dir,
                                const std::string& comment) const {
  const offline::TriangleMesh mesh = machined_mesh();
  const std::string text =
      comment.empty() ? std::string("truecut machined surface, workpiece frame, mm") : comment;
  offline::write_stl(dir / "machined.stl", mesh, offline::StlEncoding::binary, text.substr(0, 80));
  offline::write_ply(dir / "machined.ply", mesh, offline::PlyEncoding::binary_little_endian, text);
}

double DexelModel::removed_total_mm3() const {
  double sum = 0;
  for (std::size_t i = 0; i < height_.size(); ++i)
    sum += (initial_height_[i] - height_[i]) * area_[i];
  return sum;
}

}  // namespace truecut::sim::cutting
