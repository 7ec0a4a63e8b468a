#include "truecut/offline/compensation_points.hpp"

#include "truecut/offline/mesh_geometry.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <unordered_map>

namespace truecut::offline {

namespace {

void check_labels(const TriangleMesh& mesh, std::span<const std::int32_t> ids) {
  if (ids.size() != mesh.triangles.size()) {
    throw std::invalid_argument(std::to_string(ids.size()) + " surface ids for " +
                                std::to_string(mesh.triangles.size()) + " triangles");
  }
}

bool selected(std::span<const std::int32_t> surfaces, std::int32_t id) {
  return surfaces.empty() || std::find(surfaces.begin(), surfaces.end(), id) != surfaces.end();
}

}  // namespace

CompensationPoints compensation_points_at_vertices(
    const TriangleMesh& nominal, std::span<const std::int32_t> triangle_surface_ids,
    std::span<const std::int32_t> surfaces) {
  check_labels(nominal, triangle_surface_ids);
  std::vector<std::uint32_t> owner(nominal.vertices_mm.size(), kNoTriangle);
  for (std::size_t t = 0; t < nominal.triangles.size(); ++t) {
    if (!selected(surfaces, triangle_surface_ids[t])) continue;
    for (std::uint32_t v : nominal.triangles[t]) {
      if (owner[v] == kNoTriangle) owner[v] = static_cast<std::uint32_t>(t);
    }
  }
  const std::vector<Eigen::Vector3d> normals = vertex_normals(nominal);
  CompensationPoints out;
  for (std::size_t v = 0; v < owner.size(); ++v) {
    if (owner[v] == kNoTriangle) continue;
    out.positions_mm.push_back(nominal.vertices_mm[v]);
    out.normals.push_back(normals[v]);
    out.surface_ids.push_back(triangle_surface_ids[owner[v]]);
    out.triangles.push_back(owner[v]);
  }
  return out;
}

CompensationPoints sample_compensation_points(const TriangleMesh& nominal,
                                              std::span<const std::int32_t> triangle_surface_ids,
                                              double spacing_mm,
                                              std::span<const std::int32_t> surfaces) {
  check_labels(nominal, triangle_surface_ids);
  if (!(spacing_mm > 0.0)) throw std::invalid_argument("sampling spacing must be positive");
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  for (const Eigen::Vector3d& p : nominal.vertices_mm)
    lo = lo.cwiseMin(p);
  const std::vector<Eigen::Vector3d> fn = face_normals(nominal);
  const double h = spacing_mm / 4.0;

  struct Cell {
    std::int32_t surface;
    std::int64_t i, j, k;
    bool operator==(const Cell&) const = default;
  };
  struct CellHash {
    std::size_t operator()(const Cell& c) const {
      std::uint64_t x = static_cast<std::uint64_t>(c.surface) * 0x9E3779B97F4A7C15ull;
      x ^= static_cast<std::uint64_t>(c.i) * 0xBF58476D1CE4E5B9ull;
      x ^= static_cast<std::uint64_t>(c.j) * 0x94D049BB133111EBull;
      x ^= static_cast<std::uint64_t>(c.k) * 0xD6E8FEB86659FD93ull;
      return static_cast<std::size_t>(x ^ (x >> 31));
    }
  };
  struct Candidate {
    Eigen::Vector3d p;
    std::uint32_t triangle;
    double centre_distance_sq;
  };
  std::vector<Candidate> kept;
  std::unordered_map<Cell, std::size_t, CellHash> cell_of;

  auto offer = [&](const Eigen::Vector3d& p, std::uint32_t t) {
    const Eigen::Vector3d q = (p - lo) / spacing_mm;
    const Cell cell{triangle_surface_ids[t], static_cast<std::int64_t>(std::floor(q.x())),
                    static_cast<std::int64_t>(std::floor(q.y())),
                    static_cast<std::int64_t>(std::floor(q.z()))};
    const Eigen::Vector3d centre(cell.i + 0.5, cell.j + 0.5, cell.k + 0.5);
    const double d2 = (q - centre).squaredNorm();
    auto [it, fresh] = cell_of.try_emplace(cell, kept.size());
    if (fresh) {
      kept.push_back({p, t, d2});
    } else if (d2 < kept[it->second].centre_distance_sq) {  // earlier wins ties
      kept[it->second] = {p, t, d2};
    }
  };

  for (std::size_t t = 0; t < nominal.triangles.size(); ++t) {
    if (!selected(surfaces, triangle_surface_ids[t])) continue;
    const Triangle& tri = nominal.triangles[t];
    // Lattice spanned from the corner at the shortest edge, so slivers get
    // few candidates across and many along.
    int corner = 0;
    double shortest = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 3; ++k) {
      const double len =
          (nominal.vertices_mm[tri[(k + 1) % 3]] - nominal.vertices_mm[tri[k]]).norm();
      if (len < shortest) {
        shortest = len;
        corner = k;
      }
    }
    const Eigen::Vector3d& a = nominal.vertices_mm[tri[corner]];
    const Eigen::Vector3d e1 = nominal.vertices_mm[tri[(corner + 1) % 3]] - a;
    const Eigen::Vector3d e2 = nominal.vertices_mm[tri[(corner + 2) % 3]] - a;
    const int ns = std::max(1, static_cast<int>(std::ceil(e1.norm() / h)));
    const int nt = std::max(1, static_cast<int>(std::ceil(e2.norm() / h)));
    bool any = false;
    for (int i = 0; i < ns; ++i) {
      for (int j = 0; j < nt; ++j) {
        const double s = (i + 0.5) / ns, r = (j + 0.5) / nt;
        if (s + r >= 1.0) continue;
        offer(a + s * e1 + r * e2, static_cast<std::uint32_t>(t));
        any = true;
      }
    }
    if (!any) offer(a + (e1 + e2) / 3.0, static_cast<std::uint32_t>(t));
  }

  CompensationPoints out;
  std::vector<std::size_t> order(kept.size());
  for (std::size_t i = 0; i < order.size(); ++i)
    order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) {
    return kept[x].triangle < kept[y].triangle;
  });
  for (std::size_t i : order) {
    out.positions_mm.push_back(kept[i].p);
    out.normals.push_back(fn[kept[i].triangle]);
    out.surface_ids.push_back(triangle_surface_ids[kept[i].triangle]);
    out.triangles.push_back(kept[i].triangle);
  }
  return out;
}

}  // namespace truecut::offline
