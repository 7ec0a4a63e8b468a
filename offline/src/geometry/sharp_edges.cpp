#include "geometry/sharp_edges.hpp"

#include "truecut/offline/mesh_geometry.hpp"

#include <algorithm>
#include <cmath>

namespace truecut::offline::geometry {

SharpEdges::SharpEdges(const TriangleMesh& mesh, double sharp_edge_deg, double max_query_mm) {
  const double piece_mm = std::max(max_query_mm, 0.25);
  std::vector<Eigen::Vector3d> mids;
  for (const MeshEdge& e : mesh_edges(mesh, face_normals(mesh))) {
    if (e.manifold() && e.dihedral_deg <= sharp_edge_deg) continue;
    ++edges_;
    const Eigen::Vector3d& a = mesh.vertices_mm[e.v0];
    const Eigen::Vector3d& b = mesh.vertices_mm[e.v1];
    const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / piece_mm)));
    for (int k = 0; k < n; ++k) {
      const Piece piece{k == 0 ? a : Eigen::Vector3d(a + (b - a) * (double(k) / n)),
                        k + 1 == n ? b : Eigen::Vector3d(a + (b - a) * (double(k + 1) / n))};
      half_piece_mm_ = std::max(half_piece_mm_, 0.5 * (piece.b - piece.a).norm());
      pieces_.push_back(piece);
      mids.push_back(0.5 * (piece.a + piece.b));
    }
  }
  midpoints_ = spatial::KdTree(mids);
}

double SharpEdges::distance_within(const Eigen::Vector3d& p, double limit_mm) const {
  thread_local std::vector<std::uint32_t> candidates;
  candidates.clear();
  // Every point of a piece is within half its length of the midpoint.
  midpoints_.within(p, limit_mm + half_piece_mm_ * (1.0 + 1e-12), candidates);
  double best = std::numeric_limits<double>::infinity();
  for (std::uint32_t i : candidates) {
    best = std::min(best, (closest_point_on_segment(p, pieces_[i].a, pieces_[i].b) - p).norm());
  }
  return best <= limit_mm ? best : std::numeric_limits<double>::infinity();
}

}  // namespace truecut::offline::geometry
