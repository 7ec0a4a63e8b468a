// The machined surface as a mesh, and the totals of the dexel model.
#include "truecut/offline/ply_io.hpp"
#include "truecut/offline/stl_io.hpp"
#include "truecut/sim/cutting/dexel_model.hpp"

namespace truecut::sim::cutting {

offline::TriangleMesh DexelModel::machined_mesh() const {
  offline::TriangleMesh mesh;
  mesh.vertices_mm.reserve(position_.size() + fixed_vertices_.size());
  for (std::size_t i = 0; i < position_.size(); ++i)
    mesh.vertices_mm.push_back(position_[i] + height_[i] * normal_[i]);
  mesh.triangles = triangles_;
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
