#include "parts/mesh_builder.hpp"

#include <cmath>

namespace truecut::sim::parts {

std::uint32_t MeshBuilder::vertex(const Eigen::Vector3d& p_mm) {
  // 1 nm keys: points computed from the same grid values weld exactly.
  const std::array<long long, 3> key{std::llround(p_mm.x() * 1e6), std::llround(p_mm.y() * 1e6),
                                     std::llround(p_mm.z() * 1e6)};
  const auto [it, inserted] =
      index_.try_emplace(key, static_cast<std::uint32_t>(mesh.vertices_mm.size()));
  if (inserted) mesh.vertices_mm.push_back(p_mm);
  return it->second;
}

void MeshBuilder::triangle(std::uint32_t a, std::uint32_t b, std::uint32_t c, int surface) {
  mesh.triangles.push_back({a, b, c});
  triangle_surface.push_back(surface);
}

void MeshBuilder::patch(const std::vector<double>& us, const std::vector<double>& vs,
                        const PatchPoint& point, bool flip, int surface, const SkipCell& skip) {
  for (std::size_t i = 0; i + 1 < us.size(); ++i) {
    for (std::size_t j = 0; j + 1 < vs.size(); ++j) {
      if (skip && skip(0.5 * (us[i] + us[i + 1]), 0.5 * (vs[j] + vs[j + 1]))) continue;
      const std::uint32_t a = vertex(point(us[i], vs[j]));
      const std::uint32_t b = vertex(point(us[i + 1], vs[j]));
      const std::uint32_t c = vertex(point(us[i + 1], vs[j + 1]));
      const std::uint32_t d = vertex(point(us[i], vs[j + 1]));
      if (flip) {
        triangle(a, c, b, surface);
        triangle(a, d, c, surface);
      } else {
        triangle(a, b, c, surface);
        triangle(a, c, d, surface);
      }
    }
  }
}

std::vector<double> lines(double a, double b, double max_step) {
  const int n = std::max(1, static_cast<int>(std::ceil(std::abs(b - a) / max_step - 1e-9)));
  std::vector<double> out(static_cast<std::size_t>(n) + 1);
  for (int i = 0; i <= n; ++i)
    out[static_cast<std::size_t>(i)] = a + (b - a) * i / n;
  out.front() = a;
  out.back() = b;
  return out;
}

std::vector<double> join(std::initializer_list<std::vector<double>> runs) {
  std::vector<double> out;
  for (const auto& run : runs) {
    for (double v : run) {
      if (out.empty() || v != out.back()) out.push_back(v);
    }
  }
  return out;
}

}  // namespace truecut::sim::parts
