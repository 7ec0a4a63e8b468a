#include "swept.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <span>
#include <stdexcept>
#include <unordered_map>
#include <vector>

#include "truecut/interp/rewrite_blend.hpp"

namespace truecut::interp::rewrite {

namespace {

// The 3 best candidates by (distance, index), nearest first.
struct Best3 {
  int count = 0;
  std::array<int, 3> index{};
  std::array<double, 3> dist{};
  void offer(int i, double d) {
    int k = count;
    while (k > 0 && (d < dist[k - 1] || (d == dist[k - 1] && i < index[k - 1]))) {
      if (k < 3) {
        dist[k] = dist[k - 1];
        index[k] = index[k - 1];
      }
      --k;
    }
    if (k < 3) {
      dist[k] = d;
      index[k] = i;
      count = std::min(count + 1, 3);
    }
  }
};

void add_blend(const NeighbourSearch& s, const Best3& best, const Eigen::Vector3d& query,
               SweptCorrection& out) {
  if (best.count == 0) return;
  Eigen::Vector3d p[3], v[3];
  for (int i = 0; i < best.count; ++i) {
    p[i] = s.position(best.index[i]);
    v[i] = s.vector(best.index[i]);
  }
  const BlendResult b =
      blend_compensation(std::span(p, best.count), std::span(v, best.count), query);
  out.correction_mm += b.correction_mm;
  ++out.blends;
  ++out.blends_by_points[b.points_used];
}

// The extent of the points along `axis` from `tip`.
void height_range(const NeighbourSearch& s, const Eigen::Vector3d& tip, const Eigen::Vector3d& axis,
                  double& lo, double& hi) {
  lo = std::numeric_limits<double>::infinity();
  hi = -lo;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d corner((c & 1 ? s.upper_mm() : s.lower_mm()).x(),
                                 (c & 2 ? s.upper_mm() : s.lower_mm()).y(),
                                 (c & 4 ? s.upper_mm() : s.lower_mm()).z());
    const double h = (corner - tip).dot(axis);
    lo = std::min(lo, h);
    hi = std::max(hi, h);
  }
}

struct FlankCandidate {
  double h;       // along the axis from the tip
  double offset;  // radial distance from the cutting circle, r - R
  int index;
};

SweptCorrection flank(const NeighbourSearch& s, const ToolPoint& tool, double length_mm,
                      double band_mm) {
  SweptCorrection out;
  const double reach = s.reach_mm(), radius = s.radius_mm();
  const Eigen::Vector3d& t = tool.tip_mm;
  const Eigen::Vector3d& a = tool.axis;
  double box_lo = 0, box_hi = 0;
  height_range(s, t, a, box_lo, box_hi);
  const double h_lo = std::max(-reach, box_lo), h_hi = std::min(length_mm + reach, box_hi);
  if (h_lo > h_hi) return out;
  const Eigen::Vector3d e0 = t + h_lo * a, e1 = t + h_hi * a;
  const Eigen::Vector3d pad = Eigen::Vector3d::Constant(radius + reach);
  std::vector<int> near;
  s.points_near_box(e0.cwiseMin(e1) - pad, e0.cwiseMax(e1) + pad, near);
  std::vector<FlankCandidate> cand;
  for (int i : near) {
    const Eigen::Vector3d d = s.position(i) - t;
    const double h = d.dot(a);
    if (h < h_lo || h > h_hi) continue;
    const double offset = (d - h * a).norm() - radius;
    if (std::fabs(offset) <= reach) cand.push_back({h, offset, i});
  }
  if (cand.empty()) return out;
  std::sort(cand.begin(), cand.end(), [](const FlankCandidate& x, const FlankCandidate& y) {
    return x.h < y.h || (x.h == y.h && x.index < y.index);
  });
  // Bands at j * band from the tip, where a candidate can be within reach.
  const double first = std::max(0.0, cand.front().h - reach);
  const double last = std::min(length_mm, cand.back().h + reach);
  std::size_t from = 0;
  for (auto j = static_cast<long>(std::ceil(first / band_mm - 1e-9)); j * band_mm <= last + 1e-12;
       ++j) {
    const double hj = static_cast<double>(j) * band_mm;
    while (from < cand.size() && cand[from].h < hj - reach)
      ++from;
    Best3 best;
    for (std::size_t k = from; k < cand.size() && cand[k].h <= hj + reach; ++k) {
      const double d = std::hypot(cand[k].h - hj, cand[k].offset);
      if (d <= reach) best.offer(cand[k].index, d);
    }
    add_blend(s, best, t + hj * a, out);
  }
  return out;
}

struct DiscCandidate {
  double x, y;  // in the disc's plane
  double h;     // along the axis from the tip
  int index;
};

SweptCorrection disc(const NeighbourSearch& s, const ToolPoint& tool, double band_mm) {
  SweptCorrection out;
  const double reach = s.reach_mm(), radius = s.radius_mm();
  const Eigen::Vector3d& t = tool.tip_mm;
  const Eigen::Vector3d& a = tool.axis;
  // A fixed in-plane basis for a given axis (the query grid depends on it).
  Eigen::Vector3d u = a.cross(Eigen::Vector3d::UnitX());
  if (u.norm() < 0.5) u = a.cross(Eigen::Vector3d::UnitY());
  u.normalize();
  const Eigen::Vector3d v = a.cross(u);
  const Eigen::Vector3d pad = Eigen::Vector3d::Constant(radius + reach);
  std::vector<int> near;
  s.points_near_box(t - pad, t + pad, near);
  // Candidates bucketed by reach in the plane.
  std::vector<DiscCandidate> cand;
  std::unordered_map<std::int64_t, std::vector<int>> buckets;
  auto bucket_key = [](std::int64_t i, std::int64_t j) { return i * 1'000'003 + j; };
  for (int i : near) {
    const Eigen::Vector3d d = s.position(i) - t;
    const double h = d.dot(a);
    const double x = d.dot(u), y = d.dot(v);
    if (std::fabs(h) > reach || std::hypot(x, y) > radius + reach) continue;
    buckets[bucket_key(static_cast<std::int64_t>(std::floor(x / reach)),
                       static_cast<std::int64_t>(std::floor(y / reach)))]
        .push_back(static_cast<int>(cand.size()));
    cand.push_back({x, y, h, i});
  }
  if (cand.empty()) return out;
  // Query points on rings k R / n (k = 0..n, the last on the rim), about
  // 2 pi k points on ring k: spacing about R / n everywhere, equal area each.
  const int n = radius > 0 ? std::max(1, static_cast<int>(std::ceil(radius / band_mm - 1e-9))) : 0;
  for (int k = 0; k <= n; ++k) {
    const double r = n > 0 ? radius * k / n : 0.0;
    const int m = k == 0 ? 1 : static_cast<int>(std::ceil(2 * std::numbers::pi * k - 1e-9));
    for (int i = 0; i < m; ++i) {
      const double angle = 2 * std::numbers::pi * i / m;
      const double qx = r * std::cos(angle), qy = r * std::sin(angle);
      const auto bx = static_cast<std::int64_t>(std::floor(qx / reach));
      const auto by = static_cast<std::int64_t>(std::floor(qy / reach));
      Best3 best;
      for (std::int64_t di = -1; di <= 1; ++di)
        for (std::int64_t dj = -1; dj <= 1; ++dj) {
          auto it = buckets.find(bucket_key(bx + di, by + dj));
          if (it == buckets.end()) continue;
          for (int c : it->second) {
            const DiscCandidate& p = cand[static_cast<std::size_t>(c)];
            const double d =
                std::sqrt((p.x - qx) * (p.x - qx) + (p.y - qy) * (p.y - qy) + p.h * p.h);
            if (d <= reach) best.offer(p.index, d);
          }
        }
      add_blend(s, best, t + qx * u + qy * v, out);
    }
  }
  return out;
}

}  // namespace

SweptCorrection swept_correction(const NeighbourSearch& search, const ToolPoint& tool,
                                 double length_mm, double band_mm) {
  SweptCorrection out;
  switch (search.type()) {
    case CutType::kPeripheral:
      out = flank(search, tool, length_mm, band_mm);
      break;
    case CutType::kFace:
      out = disc(search, tool, band_mm);
      break;
    case CutType::kBall:
      throw std::logic_error("swept_correction: a ball end mill cuts at its contact point");
  }
  if (out.blends > 0) out.correction_mm /= static_cast<double>(out.blends);
  return out;
}

}  // namespace truecut::interp::rewrite
