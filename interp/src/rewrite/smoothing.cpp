#include "smoothing.hpp"

#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <vector>

namespace truecut::interp::rewrite {

CompensationMatrixData smooth_matrix(const CompensationMatrixData& m, double radius_mm) {
  if (!(radius_mm > 0)) return m;
  // Valid points in cells of the radius: a point's neighbours lie in the 27
  // cells around its own.
  auto cell_of = [radius_mm](double v) {
    return static_cast<std::int64_t>(std::floor(v / radius_mm));
  };
  auto key = [](std::int64_t i, std::int64_t j, std::int64_t k) {
    return std::array<std::int64_t, 3>{i, j, k};
  };
  std::map<std::array<std::int64_t, 3>, std::vector<std::size_t>> cells;
  for (std::size_t i = 0; i < m.size(); ++i) {
    if (!m.valid[i]) continue;
    const Eigen::Vector3d& p = m.positions_mm[i];
    cells[key(cell_of(p.x()), cell_of(p.y()), cell_of(p.z()))].push_back(i);
  }
  const double sigma = radius_mm / 2;
  CompensationMatrixData out = m;
  for (std::size_t i = 0; i < m.size(); ++i) {
    if (!m.valid[i]) continue;
    const Eigen::Vector3d& p = m.positions_mm[i];
    const std::int64_t ci = cell_of(p.x()), cj = cell_of(p.y()), ck = cell_of(p.z());
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double weight = 0;
    for (std::int64_t di = -1; di <= 1; ++di)
      for (std::int64_t dj = -1; dj <= 1; ++dj)
        for (std::int64_t dk = -1; dk <= 1; ++dk) {
          auto it = cells.find(key(ci + di, cj + dj, ck + dk));
          if (it == cells.end()) continue;
          for (std::size_t j : it->second) {
            if (m.surface_ids[j] != m.surface_ids[i]) continue;
            const Eigen::Vector3d d = m.positions_mm[j] - p;
            const double d2 = d.squaredNorm();
            if (d2 > radius_mm * radius_mm) continue;
            const double w = std::exp(-d2 / (2 * sigma * sigma));
            sum += w * m.vectors_mm[j];
            weight += w;
          }
        }
    out.vectors_mm[i] = sum / weight;  // weight >= 1: the point itself
  }
  return out;
}

}  // namespace truecut::interp::rewrite
