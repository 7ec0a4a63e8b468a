// An orthographic z-buffer rasteriser with flat Lambert shading.
#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Geometry>

#include "truecut/analysis/report/deviation_image.hpp"

namespace truecut::analysis::report {

RgbImage render_mesh(const offline::TriangleMesh& mesh, const std::vector<double>& vertex_values,
                     double colour_limit, const MeshView& view) {
  RgbImage img;
  img.width = view.width_px;
  img.height = view.height_px;
  img.rgb.assign(static_cast<size_t>(img.width) * img.height * 3, 255);
  if (mesh.vertices_mm.empty() || mesh.triangles.empty()) return img;

  // Camera frame: w along the view, u to the right, v up on the screen.
  const Eigen::Vector3d w = view.view_direction.normalized();
  Eigen::Vector3d u = w.cross(view.up);
  if (u.norm() < 1e-9) u = w.cross(Eigen::Vector3d::UnitX());
  u.normalize();
  const Eigen::Vector3d v = u.cross(w);

  // Fit the view to the vertices that carry a value (the judged surfaces),
  // or to the whole mesh when none does.
  std::size_t valued = 0;
  for (std::size_t i = 0; i < mesh.vertices_mm.size() && i < vertex_values.size(); ++i)
    valued += std::isfinite(vertex_values[i]) ? 1 : 0;
  double umin = std::numeric_limits<double>::max(), umax = -umin, vmin = umin, vmax = -umin;
  for (std::size_t i = 0; i < mesh.vertices_mm.size(); ++i) {
    if (valued >= 3 && !(i < vertex_values.size() && std::isfinite(vertex_values[i]))) continue;
    const Eigen::Vector3d& p = mesh.vertices_mm[i];
    umin = std::min(umin, p.dot(u)), umax = std::max(umax, p.dot(u));
    vmin = std::min(vmin, p.dot(v)), vmax = std::max(vmax, p.dot(v));
  }
  const double margin = 0.04;
  const double span = std::max({(umax - umin) / img.width, (vmax - vmin) / img.height, 1e-9});
  const double scale = (1.0 - 2 * margin) / span;  // px per mm
  const double cu = 0.5 * (umin + umax), cv = 0.5 * (vmin + vmax);
  auto to_px = [&](const Eigen::Vector3d& p) {
    return Eigen::Vector3d(0.5 * img.width + (p.dot(u) - cu) * scale,
                           0.5 * img.height - (p.dot(v) - cv) * scale, p.dot(w));
  };

  std::vector<double> depth(static_cast<size_t>(img.width) * img.height,
                            std::numeric_limits<double>::infinity());
  const Eigen::Vector3d light = (-w + 0.6 * v - 0.3 * u).normalized();
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d& p0 = mesh.vertices_mm[t[0]];
    const Eigen::Vector3d& p1 = mesh.vertices_mm[t[1]];
    const Eigen::Vector3d& p2 = mesh.vertices_mm[t[2]];
    Eigen::Vector3d n = (p1 - p0).cross(p2 - p0);
    if (n.norm() == 0) continue;
    n.normalize();
    if (n.dot(w) > 0) continue;  // back face: closed meshes show their outside
    double value = 0;
    bool known = true;
    for (int k = 0; k < 3; ++k) {
      const double s = t[k] < vertex_values.size() ? vertex_values[t[k]]
                                                   : std::numeric_limits<double>::quiet_NaN();
      known = known && std::isfinite(s);
      value += s / 3.0;
    }
    auto base =
        deviation_colour(known ? value : std::numeric_limits<double>::quiet_NaN(), colour_limit);
    const double shade = 0.35 + 0.65 * std::max(0.0, n.dot(light));
    const Eigen::Vector3d a = to_px(p0), b = to_px(p1), c = to_px(p2);
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min({a.x(), b.x(), c.x()}))));
    const int x1 =
        std::min(img.width - 1, static_cast<int>(std::ceil(std::max({a.x(), b.x(), c.x()}))));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min({a.y(), b.y(), c.y()}))));
    const int y1 =
        std::min(img.height - 1, static_cast<int>(std::ceil(std::max({a.y(), b.y(), c.y()}))));
    const double area = (b.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (b.y() - a.y());
    if (std::abs(area) < 1e-12) continue;
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const double px = x + 0.5, py = y + 0.5;
        const double l0 = ((b.x() - px) * (c.y() - py) - (c.x() - px) * (b.y() - py)) / area;
        const double l1 = ((c.x() - px) * (a.y() - py) - (a.x() - px) * (c.y() - py)) / area;
        const double l2 = 1.0 - l0 - l1;
        if (l0 < 0 || l1 < 0 || l2 < 0) continue;
        const double z = l0 * a.z() + l1 * b.z() + l2 * c.z();
        const size_t i = static_cast<size_t>(y) * img.width + x;
        if (z >= depth[i]) continue;
        depth[i] = z;
        for (int k = 0; k < 3; ++k)
          img.rgb[i * 3 + k] = static_cast<std::uint8_t>(std::lround(base[k] * shade));
      }
    }
  }
  return img;
}

}  // namespace truecut::analysis::report
