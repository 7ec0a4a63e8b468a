// Distance from a point to the nearest sharp edge of a mesh (dihedral angle
// above a threshold, boundary or non-manifold), exact in double. Long edges
// are cut into pieces so a k-d tree over the piece midpoints finds the
// candidates for a fixed-radius question.
#pragma once

#include "spatial/kd_tree.hpp"
#include "truecut/offline/mesh.hpp"

#include <limits>
#include <vector>

namespace truecut::offline::geometry {

class SharpEdges {
 public:
  SharpEdges(const TriangleMesh& mesh, double sharp_edge_deg, double max_query_mm);

  // The distance to the nearest sharp edge if it is at most limit_mm
  // (≤ max_query_mm), else infinity.
  double distance_within(const Eigen::Vector3d& p, double limit_mm) const;
  std::size_t edge_count() const { return edges_; }

 private:
  struct Piece {
    Eigen::Vector3d a, b;
  };
  std::vector<Piece> pieces_;
  spatial::KdTree midpoints_;
  double half_piece_mm_ = 0.0;
  std::size_t edges_ = 0;
};

}  // namespace truecut::offline::geometry
