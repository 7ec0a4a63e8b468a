#include "scan_surface.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <cstdlib>

namespace truecut::sim::measure::detail {
namespace {

constexpr int kNormalRadiusCells = 2;
constexpr int kMinNormalPoints = 5;

}  // namespace

void estimate_grid_normals(const MeasuredGrid& grid, const std::vector<Eigen::Vector3d>& points_mm,
                           const std::vector<Eigen::Vector3d>& ray_dirs,
                           std::vector<Eigen::Vector3d>& normals) {
  const long rows = static_cast<long>(grid.rows), cols = static_cast<long>(grid.cols);
  std::array<Eigen::Vector3d, (2 * kNormalRadiusCells + 1) * (2 * kNormalRadiusCells + 1)> near;
  for (long r = 0; r < rows; ++r) {
    for (long c = 0; c < cols; ++c) {
      const std::int32_t self = grid.point[static_cast<std::size_t>(r * cols + c)];
      if (self < 0) continue;
      const Eigen::Vector3d& p = points_mm[static_cast<std::size_t>(self)];
      const Eigen::Vector3d toward_scanner = -ray_dirs[static_cast<std::size_t>(self)];
      const double limit = grid.edge_limit_mm(p);
      int count = 0;
      for (long dr = -kNormalRadiusCells; dr <= kNormalRadiusCells; ++dr) {
        for (long dc = -kNormalRadiusCells; dc <= kNormalRadiusCells; ++dc) {
          const long rr = r + dr, cc = c + dc;
          if (rr < 0 || rr >= rows || cc < 0 || cc >= cols) continue;
          const std::int32_t other = grid.point[static_cast<std::size_t>(rr * cols + cc)];
          if (other < 0) continue;
          const Eigen::Vector3d& q = points_mm[static_cast<std::size_t>(other)];
          const double cells = static_cast<double>(std::max(std::labs(dr), std::labs(dc)));
          if ((q - p).norm() > cells * limit) continue;
          near[static_cast<std::size_t>(count++)] = q;
        }
      }
      Eigen::Vector3d n = toward_scanner;
      if (count >= kMinNormalPoints) {
        Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
        for (int i = 0; i < count; ++i)
          centroid += near[static_cast<std::size_t>(i)];
        centroid /= count;
        Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
        for (int i = 0; i < count; ++i) {
          const Eigen::Vector3d d = near[static_cast<std::size_t>(i)] - centroid;
          cov += d * d.transpose();
        }
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
        // Eigenvalues ascending: the plane normal has the smallest; a
        // collinear neighbourhood (two small ones) keeps the view direction.
        if (eig.info() == Eigen::Success && eig.eigenvalues()(1) > 4.0 * eig.eigenvalues()(0)) {
          n = eig.eigenvectors().col(0).normalized();
          if (n.dot(toward_scanner) < 0) n = -n;
        }
      }
      normals[static_cast<std::size_t>(self)] = n;
    }
  }
}

void triangulate_grid(const MeasuredGrid& grid, const std::vector<Eigen::Vector3d>& points_mm,
                      const std::vector<Eigen::Vector3d>& ray_dirs,
                      std::vector<offline::Triangle>& triangles) {
  const std::size_t rows = grid.rows, cols = grid.cols;
  auto add = [&](std::int32_t a, std::int32_t b, std::int32_t c) {
    const Eigen::Vector3d& pa = points_mm[static_cast<std::size_t>(a)];
    const Eigen::Vector3d& pb = points_mm[static_cast<std::size_t>(b)];
    const Eigen::Vector3d& pc = points_mm[static_cast<std::size_t>(c)];
    const double limit = grid.edge_limit_mm(pa);
    if ((pb - pa).norm() > limit || (pc - pb).norm() > limit || (pa - pc).norm() > limit) return;
    const Eigen::Vector3d n = (pb - pa).cross(pc - pa);
    if (!(n.squaredNorm() > 0)) return;
    const auto ua = static_cast<std::uint32_t>(a), ub = static_cast<std::uint32_t>(b),
               uc = static_cast<std::uint32_t>(c);
    if (n.dot(ray_dirs[static_cast<std::size_t>(a)]) < 0)
      triangles.push_back({ua, ub, uc});
    else
      triangles.push_back({ua, uc, ub});
  };
  for (std::size_t r = 0; r + 1 < rows; ++r) {
    for (std::size_t c = 0; c + 1 < cols; ++c) {
      const std::int32_t p00 = grid.point[r * cols + c], p01 = grid.point[r * cols + c + 1];
      const std::int32_t p10 = grid.point[(r + 1) * cols + c],
                         p11 = grid.point[(r + 1) * cols + c + 1];
      const int valid = (p00 >= 0) + (p01 >= 0) + (p10 >= 0) + (p11 >= 0);
      if (valid == 4) {
        const auto at = [&](std::int32_t i) -> const Eigen::Vector3d& {
          return points_mm[static_cast<std::size_t>(i)];
        };
        if ((at(p00) - at(p11)).squaredNorm() <= (at(p01) - at(p10)).squaredNorm()) {
          add(p00, p01, p11);
          add(p00, p11, p10);
        } else {
          add(p00, p01, p10);
          add(p01, p11, p10);
        }
      } else if (valid == 3) {
        std::array<std::int32_t, 3> corners{};
        int k = 0;
        for (std::int32_t i : {p00, p01, p11, p10})
          if (i >= 0) corners[static_cast<std::size_t>(k++)] = i;
        add(corners[0], corners[1], corners[2]);
      }
    }
  }
}

}  // namespace truecut::sim::measure::detail
