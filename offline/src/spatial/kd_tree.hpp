// A static k-d tree over 3-D points for nearest-neighbour and fixed-radius
// queries. Balanced by construction: every node splits its index range at the
// median along the widest axis of the range's bounding box, so the tree is
// implicit (node i has children 2i+1, 2i+2; a node's range follows from its
// position) and only the split planes are stored. Queries are const and may
// run concurrently.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

namespace truecut::offline::spatial {

class KdTree {
 public:
  static constexpr std::uint32_t kNone = 0xffffffffu;

  KdTree() = default;
  explicit KdTree(std::span<const Eigen::Vector3d> points);

  struct Nearest {
    std::uint32_t index = kNone;  // into the points given to the constructor
    double distance_sq = std::numeric_limits<double>::infinity();
  };
  // The nearest point strictly closer than max_distance (ties: the lower
  // index), or index kNone.
  Nearest nearest(const Eigen::Vector3d& q,
                  double max_distance = std::numeric_limits<double>::infinity()) const;

  // The k nearest points strictly closer than max_distance, nearest first
  // (ties: the lower index), written to `out` (cleared first). Every point
  // strictly closer to q than the last one returned is among them; with
  // fewer than k returned, every point strictly closer than max_distance.
  void nearest_k(const Eigen::Vector3d& q, std::size_t k, double max_distance,
                 std::vector<Nearest>& out) const;

  // Appends the indices of all points within `radius` (inclusive) to `out`,
  // in the tree's order: fixed by the points alone, the same for every call.
  void within(const Eigen::Vector3d& q, double radius, std::vector<std::uint32_t>& out) const;

  std::size_t size() const { return items_.size(); }

 private:
  struct Split {
    double value = 0.0;
    std::uint8_t axis = 0;
  };
  // lo/hi bound the range's points: the parent's bounds cut at its split,
  // which is enough to pick the axis to split.
  void build(std::uint32_t node, std::uint32_t begin, std::uint32_t end, int depth,
             Eigen::Vector3d lo, Eigen::Vector3d hi);
  void nearest_in(std::uint32_t node, std::uint32_t begin, std::uint32_t end, int depth,
                  const Eigen::Vector3d& q, Nearest& best) const;
  void nearest_k_in(std::uint32_t node, std::uint32_t begin, std::uint32_t end, int depth,
                    const Eigen::Vector3d& q, std::size_t k, double& bound_sq,
                    std::vector<Nearest>& heap) const;
  // box_sq: the squared distance from q to the node's cell, off: its part
  // along each axis (the cell bounded by the splits above).
  void within_in(std::uint32_t node, std::uint32_t begin, std::uint32_t end, int depth,
                 const Eigen::Vector3d& q, double r2, double box_sq, std::array<double, 3>& off,
                 std::vector<std::uint32_t>& out) const;

  struct Item {
    Eigen::Vector3d p;
    std::uint32_t index;  // in the input
  };
  std::vector<Item> items_;    // in tree order
  std::vector<Split> splits_;  // 2^depth_ - 1 internal nodes
  int depth_ = 0;
};

}  // namespace truecut::offline::spatial
