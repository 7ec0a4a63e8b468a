#include "spatial/kd_tree.hpp"

#include <tbb/parallel_invoke.h>

#include <algorithm>

namespace truecut::offline::spatial {

namespace {
constexpr std::uint32_t kLeafSize = 8;
// Subtrees larger than this are built as parallel tasks.
constexpr std::uint32_t kParallelBuild = 1u << 15;
constexpr int kTightBoundsDepth = 6;
// A cell's distance is built up by sums and differences, so it may round
// above a point's own distance on the sphere: cells are kept that little
// beyond the radius (the points themselves are tested exactly).
constexpr double kCellSlack = 1.0 + 1e-9;
}  // namespace

KdTree::KdTree(std::span<const Eigen::Vector3d> points) {
  const auto n = static_cast<std::uint32_t>(points.size());
  while ((n >> depth_) > kLeafSize)
    ++depth_;
  splits_.resize((std::size_t{1} << depth_) - 1);
  items_.resize(n);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (std::uint32_t i = 0; i < n; ++i) {
    items_[i] = {points[i], i};
    lo = lo.cwiseMin(points[i]);
    hi = hi.cwiseMax(points[i]);
  }
  if (n > 0) build(0, 0, n, 0, lo, hi);
}

void KdTree::build(std::uint32_t node, std::uint32_t begin, std::uint32_t end, int depth,
                   Eigen::Vector3d lo, Eigen::Vector3d hi) {
  if (depth == depth_) return;
  // Tight bounds on the upper levels, where a well-chosen axis pays most.
  if (depth < kTightBoundsDepth) {
    lo.setConstant(std::numeric_limits<double>::infinity());
    hi = -lo;
    for (std::uint32_t i = begin; i < end; ++i) {
      lo = lo.cwiseMin(items_[i].p);
      hi = hi.cwiseMax(items_[i].p);
    }
  }
  Eigen::Index axis = 0;
  (hi - lo).maxCoeff(&axis);
  const std::uint32_t mid = begin + (end - begin) / 2;
  std::nth_element(items_.begin() + begin, items_.begin() + mid, items_.begin() + end,
                   [axis](const Item& a, const Item& b) { return a.p[axis] < b.p[axis]; });
  const double split = items_[mid].p[axis];
  splits_[node] = {split, static_cast<std::uint8_t>(axis)};
  Eigen::Vector3d left_hi = hi, right_lo = lo;
  left_hi[axis] = split;
  right_lo[axis] = split;
  if (end - begin > kParallelBuild) {
    tbb::parallel_invoke([&] { build(2 * node + 1, begin, mid, depth + 1, lo, left_hi); },
                         [&] { build(2 * node + 2, mid, end, depth + 1, right_lo, hi); });
  } else {
    build(2 * node + 1, begin, mid, depth + 1, lo, left_hi);
    build(2 * node + 2, mid, end, depth + 1, right_lo, hi);
  }
}

KdTree::Nearest KdTree::nearest(const Eigen::Vector3d& q, double max_distance) const {
  Nearest best;
  best.distance_sq = max_distance * max_distance;
  if (!items_.empty()) nearest_in(0, 0, static_cast<std::uint32_t>(items_.size()), 0, q, best);
  if (best.index != kNone) best.index = items_[best.index].index;
  return best;
}

// best.index holds a tree-order position until nearest() maps it back.
void KdTree::nearest_in(std::uint32_t node, std::uint32_t begin, std::uint32_t end, int depth,
                        const Eigen::Vector3d& q, Nearest& best) const {
  if (depth == depth_) {
    for (std::uint32_t i = begin; i < end; ++i) {
      const double d2 = (items_[i].p - q).squaredNorm();
      // Ties go to the lower input index, so the result does not depend on
      // the tree's layout.
      if (d2 < best.distance_sq || (d2 == best.distance_sq && best.index != kNone &&
                                    items_[i].index < items_[best.index].index)) {
        best.distance_sq = d2;
        best.index = i;
      }
    }
    return;
  }
  const Split s = splits_[node];
  const std::uint32_t mid = begin + (end - begin) / 2;
  const double delta = q[s.axis] - s.value;
  if (delta < 0.0) {
    nearest_in(2 * node + 1, begin, mid, depth + 1, q, best);
    if (delta * delta <= best.distance_sq) nearest_in(2 * node + 2, mid, end, depth + 1, q, best);
  } else {
    nearest_in(2 * node + 2, mid, end, depth + 1, q, best);
    if (delta * delta <= best.distance_sq) nearest_in(2 * node + 1, begin, mid, depth + 1, q, best);
  }
}

namespace {
// Strict order on (distance, input index); as the heap's order, its top is
// the worst point kept.
bool closer(const KdTree::Nearest& a, const KdTree::Nearest& b) {
  return a.distance_sq < b.distance_sq || (a.distance_sq == b.distance_sq && a.index < b.index);
}
}  // namespace

void KdTree::nearest_k(const Eigen::Vector3d& q, std::size_t k, double max_distance,
                       std::vector<Nearest>& out) const {
  out.clear();
  if (items_.empty() || k == 0) return;
  double bound_sq = max_distance * max_distance;
  nearest_k_in(0, 0, static_cast<std::uint32_t>(items_.size()), 0, q, k, bound_sq, out);
  std::sort_heap(out.begin(), out.end(), closer);
}

// `heap` holds input indices in heap order by `closer`. bound_sq is
// max_distance² until k points are held, then the k-th distance (a point
// that far may still replace the top on a tie with a lower index, hence <=
// when descending).
void KdTree::nearest_k_in(std::uint32_t node, std::uint32_t begin, std::uint32_t end, int depth,
                          const Eigen::Vector3d& q, std::size_t k, double& bound_sq,
                          std::vector<Nearest>& heap) const {
  if (depth == depth_) {
    for (std::uint32_t i = begin; i < end; ++i) {
      const Nearest candidate{items_[i].index, (items_[i].p - q).squaredNorm()};
      if (heap.size() < k) {
        if (!(candidate.distance_sq < bound_sq)) continue;
        heap.push_back(candidate);
        std::push_heap(heap.begin(), heap.end(), closer);
        if (heap.size() == k) bound_sq = heap.front().distance_sq;
      } else if (closer(candidate, heap.front())) {
        std::pop_heap(heap.begin(), heap.end(), closer);
        heap.back() = candidate;
        std::push_heap(heap.begin(), heap.end(), closer);
        bound_sq = heap.front().distance_sq;
      }
    }
    return;
  }
  const Split s = splits_[node];
  const std::uint32_t mid = begin + (end - begin) / 2;
  const double delta = q[s.axis] - s.value;
  if (delta < 0.0) {
    nearest_k_in(2 * node + 1, begin, mid, depth + 1, q, k, bound_sq, heap);
    if (delta * delta <= bound_sq)
      nearest_k_in(2 * node + 2, mid, end, depth + 1, q, k, bound_sq, heap);
  } else {
    nearest_k_in(2 * node + 2, mid, end, depth + 1, q, k, bound_sq, heap);
    if (delta * delta <= bound_sq)
      nearest_k_in(2 * node + 1, begin, mid, depth + 1, q, k, bound_sq, heap);
  }
}

void KdTree::within(const Eigen::Vector3d& q, double radius,
                    std::vector<std::uint32_t>& out) const {
  if (!items_.empty() && radius >= 0.0) {
    std::array<double, 3> off{0.0, 0.0, 0.0};
    within_in(0, 0, static_cast<std::uint32_t>(items_.size()), 0, q, radius * radius, 0.0, off,
              out);
  }
}

// A child is entered only when its whole cell may reach the ball (the
// distance to the cell, built up split by split: Arya and Mount's
// incremental distance), always left before right, so the points come out
// in tree order whatever the query.
void KdTree::within_in(std::uint32_t node, std::uint32_t begin, std::uint32_t end, int depth,
                       const Eigen::Vector3d& q, double r2, double box_sq,
                       std::array<double, 3>& off, std::vector<std::uint32_t>& out) const {
  if (depth == depth_) {
    for (std::uint32_t i = begin; i < end; ++i) {
      if ((items_[i].p - q).squaredNorm() <= r2) out.push_back(items_[i].index);
    }
    return;
  }
  const Split s = splits_[node];
  const std::uint32_t mid = begin + (end - begin) / 2;
  const double delta = q[s.axis] - s.value;
  const double old = off[s.axis];
  // Left cell: up to the split; q beyond it (delta > 0) is delta away along the axis.
  if (delta <= 0.0) {
    within_in(2 * node + 1, begin, mid, depth + 1, q, r2, box_sq, off, out);
  } else {
    const double left_sq = box_sq - old * old + delta * delta;
    if (left_sq <= r2 * kCellSlack) {
      off[s.axis] = delta;
      within_in(2 * node + 1, begin, mid, depth + 1, q, r2, left_sq, off, out);
      off[s.axis] = old;
    }
  }
  if (delta >= 0.0) {
    within_in(2 * node + 2, mid, end, depth + 1, q, r2, box_sq, off, out);
  } else {
    const double right_sq = box_sq - old * old + delta * delta;
    if (right_sq <= r2 * kCellSlack) {
      off[s.axis] = -delta;
      within_in(2 * node + 2, mid, end, depth + 1, q, r2, right_sq, off, out);
      off[s.axis] = old;
    }
  }
}

}  // namespace truecut::offline::spatial
