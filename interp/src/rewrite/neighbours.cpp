#include "neighbours.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace truecut::interp::rewrite {

namespace {

constexpr std::int64_t kSpan = 1 << 20;  // cells per axis in the key

}  // namespace

std::int64_t NeighbourSearch::key(std::int64_t i, std::int64_t j, std::int64_t k) const {
  return ((i + kSpan / 2) * kSpan + (j + kSpan / 2)) * kSpan + (k + kSpan / 2);
}

std::int64_t NeighbourSearch::key(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d c = ((p - origin_mm_) / cell_mm_).array().floor();
  return key(static_cast<std::int64_t>(c.x()), static_cast<std::int64_t>(c.y()),
             static_cast<std::int64_t>(c.z()));
}

NeighbourSearch::NeighbourSearch(const CompensationMatrixData& m,
                                 const std::vector<std::int32_t>& surfaces, CutType type,
                                 double radius_mm, double reach_mm)
    : type_(type), radius_mm_(radius_mm) {
  for (size_t i = 0; i < m.size(); ++i) {
    if (!m.valid[i]) continue;
    if (!surfaces.empty() &&
        std::find(surfaces.begin(), surfaces.end(), m.surface_ids[i]) == surfaces.end())
      continue;
    positions_.push_back(m.positions_mm[i]);
    vectors_.push_back(m.vectors_mm[i]);
  }
  if (positions_.empty())
    throw RewriteError(surfaces.empty()
                           ? "the compensation matrix has no valid point"
                           : "the compensation matrix has no valid point on the chosen surfaces");
  Eigen::Vector3d lo = positions_[0], hi = positions_[0];
  for (const auto& p : positions_) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  origin_mm_ = lo;
  lower_mm_ = lo;
  upper_mm_ = hi;
  // First grid: about one point per cell for points spread over surfaces.
  const double diag = (hi - lo).norm();
  cell_mm_ = std::max(diag / std::sqrt(static_cast<double>(positions_.size())), 1e-3);
  for (size_t i = 0; i < positions_.size(); ++i)
    cells_[key(positions_[i])].push_back(static_cast<int>(i));
  reach_mm_ = reach_mm > 0 ? reach_mm : std::max(2.0 * median_spacing_mm(), 1e-3);
  // Query grid: a tool point needs the points within R + reach of its
  // reference point, so cells of that size and the 27 around it suffice.
  cell_mm_ = std::max(radius_mm_ + reach_mm_, 1e-3);
  cells_.clear();
  for (size_t i = 0; i < positions_.size(); ++i)
    cells_[key(positions_[i])].push_back(static_cast<int>(i));
}

double NeighbourSearch::median_spacing_mm() const {
  std::vector<double> nn;
  nn.reserve(positions_.size());
  for (size_t i = 0; i < positions_.size(); ++i) {
    const Eigen::Vector3d c = ((positions_[i] - origin_mm_) / cell_mm_).array().floor();
    double best = std::numeric_limits<double>::infinity();
    for (int di = -1; di <= 1; ++di)
      for (int dj = -1; dj <= 1; ++dj)
        for (int dk = -1; dk <= 1; ++dk) {
          auto it = cells_.find(key(static_cast<std::int64_t>(c.x()) + di,
                                    static_cast<std::int64_t>(c.y()) + dj,
                                    static_cast<std::int64_t>(c.z()) + dk));
          if (it == cells_.end()) continue;
          for (int j : it->second) {
            if (j == static_cast<int>(i)) continue;
            const double d = (positions_[j] - positions_[i]).norm();
            if (d > 0 && d < best) best = d;
          }
        }
    if (std::isfinite(best)) nn.push_back(best);
  }
  if (nn.empty()) return cell_mm_;
  std::nth_element(nn.begin(), nn.begin() + nn.size() / 2, nn.end());
  return nn[nn.size() / 2];
}

void NeighbourSearch::points_near_box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                                      std::vector<int>& out) const {
  const Eigen::Vector3d a = lo.cwiseMax(lower_mm_), b = hi.cwiseMin(upper_mm_);
  if ((a.array() > b.array()).any()) return;
  const Eigen::Vector3d c0 = ((a - origin_mm_) / cell_mm_).array().floor();
  const Eigen::Vector3d c1 = ((b - origin_mm_) / cell_mm_).array().floor();
  for (auto i = static_cast<std::int64_t>(c0.x()); i <= static_cast<std::int64_t>(c1.x()); ++i)
    for (auto j = static_cast<std::int64_t>(c0.y()); j <= static_cast<std::int64_t>(c1.y()); ++j)
      for (auto k = static_cast<std::int64_t>(c0.z()); k <= static_cast<std::int64_t>(c1.z());
           ++k) {
        auto it = cells_.find(key(i, j, k));
        if (it != cells_.end()) out.insert(out.end(), it->second.begin(), it->second.end());
      }
}

Nearest NeighbourSearch::nearest(const ToolPoint& tool) const {
  Nearest out;
  const Eigen::Vector3d& t = tool.tip_mm;
  const Eigen::Vector3d& a = tool.axis;
  out.query_mm = type_ == CutType::kBall ? Eigen::Vector3d(t + radius_mm_ * a) : t;
  const Eigen::Vector3d& q = out.query_mm;
  // More than a cell outside the points' box, no cell searched below holds
  // a point; and far enough out (or NaN) a cell index is not an integer.
  if (!((q.array() >= lower_mm_.array() - cell_mm_).all() &&
        (q.array() <= upper_mm_.array() + cell_mm_).all()))
    return out;
  std::array<double, 3> rank{};
  const Eigen::Vector3d c = ((q - origin_mm_) / cell_mm_).array().floor();
  for (int di = -1; di <= 1; ++di)
    for (int dj = -1; dj <= 1; ++dj)
      for (int dk = -1; dk <= 1; ++dk) {
        auto it = cells_.find(key(static_cast<std::int64_t>(c.x()) + di,
                                  static_cast<std::int64_t>(c.y()) + dj,
                                  static_cast<std::int64_t>(c.z()) + dk));
        if (it == cells_.end()) continue;
        for (int i : it->second) {
          const Eigen::Vector3d d = positions_[i] - t;
          double gap = 0, r = 0;  // distance to the cutting part; ranking distance
          switch (type_) {
            case CutType::kBall: {
              r = (positions_[i] - q).norm();
              gap = r - radius_mm_;
              break;
            }
            case CutType::kFace: {
              const double h = d.dot(a);
              const double radial = (d - h * a).norm();
              gap = std::hypot(h, std::max(radial - radius_mm_, 0.0));
              r = d.norm();
              break;
            }
            case CutType::kPeripheral: {
              const double h = d.dot(a);
              const double radial = (d - h * a).norm();
              gap = std::hypot(h, radial - radius_mm_);
              r = gap;
              break;
            }
          }
          if (gap > reach_mm_) continue;
          // Insert into the 3 best by (rank, index) so ties are deterministic.
          int k = out.count;
          while (k > 0 && (r < rank[k - 1] || (r == rank[k - 1] && i < out.index[k - 1]))) {
            if (k < 3) {
              rank[k] = rank[k - 1];
              out.index[k] = out.index[k - 1];
            }
            --k;
          }
          if (k < 3) {
            rank[k] = r;
            out.index[k] = i;
            out.count = std::min(out.count + 1, 3);
          }
        }
      }
  return out;
}

}  // namespace truecut::interp::rewrite
