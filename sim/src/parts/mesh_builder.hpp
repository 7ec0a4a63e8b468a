// Builds closed meshes from parametric grid patches. Vertices are welded by
// position, so patches whose border grid lines coincide share their edges.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <vector>

#include "truecut/offline/mesh.hpp"

namespace truecut::sim::parts {

class MeshBuilder {
 public:
  std::uint32_t vertex(const Eigen::Vector3d& p_mm);
  // a b c counter-clockwise seen from outside.
  void triangle(std::uint32_t a, std::uint32_t b, std::uint32_t c, int surface);

  using PatchPoint = std::function<Eigen::Vector3d(double u, double v)>;
  using SkipCell = std::function<bool(double u_mid, double v_mid)>;
  // Grid cells between consecutive u and v lines, two triangles each. The
  // outward side is that of ∂u × ∂v unless `flip`.
  void patch(const std::vector<double>& us, const std::vector<double>& vs, const PatchPoint& point,
             bool flip, int surface, const SkipCell& skip = {});

  offline::TriangleMesh mesh;
  std::vector<int> triangle_surface;

 private:
  std::map<std::array<long long, 3>, std::uint32_t> index_;
};

// n+1 evenly spaced values from a to b with n = max(1, ceil(|b−a| / max_step));
// the ends are exactly a and b.
std::vector<double> lines(double a, double b, double max_step);
// Concatenation of runs, dropping the repeated joint values.
std::vector<double> join(std::initializer_list<std::vector<double>> runs);

}  // namespace truecut::sim::parts
