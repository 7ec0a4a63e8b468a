// The machined surface as a mesh, and the totals of the dexel model.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <Eigen/Geometry>

#include "truecut/offline/ply_io.hpp"
#include "truecut/offline/stl_io.hpp"
#include "truecut/sim/cutting/dexel_model.hpp"
#include "truecut/sim/soft_cnc_outputs.hpp"
#include "worker_pool.hpp"

namespace truecut::sim::cutting {

namespace {

constexpr std::uint32_t kNoSplit = 0xFFFFFFFFu;

// The surface a tool instance swept locally (DexelModel::sweep_kind_).
struct SweptSurface {
  std::uint8_t kind = 0;  // DexelModel::kSwept*
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d vector = Eigen::Vector3d::Zero();
  double radius = 0;
};

// Where the line x0 + t·n (t outwards) enters the tool side of the swept
// surface: the smaller root for a tube (radius r about the line through the
// ball centre along unit v; v = 0: the ball), the plane's crossing when its
// normal faces along the line; +inf when the line misses it.
double entry(const SweptSurface& s, const Eigen::Vector3d& x0, const Eigen::Vector3d& n) {
  constexpr double kNone = std::numeric_limits<double>::infinity();
  if (s.kind == 2) {
    const double along = s.vector.dot(n);
    return along > 0.05 ? s.vector.dot(s.point - x0) / along : kNone;
  }
  Eigen::Vector3d q = x0 - s.point, m = n;
  q -= q.dot(s.vector) * s.vector;
  m -= m.dot(s.vector) * s.vector;
  const double a = m.squaredNorm(), b = 2 * q.dot(m), c = q.squaredNorm() - s.radius * s.radius;
  const double disc = b * b - 4 * a * c;
  if (a < 1e-18 || disc < 0) return kNone;
  return (-b - std::sqrt(disc)) / (2 * a);
}

// The triangle (c0, c1, c2) with its edges c_k → c_(k+1) split at m[k]
// (kNoSplit: not split), in the same orientation.
void emit_split(const std::uint32_t c[3], const std::uint32_t m[3],
                const std::vector<Eigen::Vector3d>& v, std::vector<offline::Triangle>& out) {
  const int count = (m[0] != kNoSplit) + (m[1] != kNoSplit) + (m[2] != kNoSplit);
  if (count == 0) {
    out.push_back({c[0], c[1], c[2]});
  } else if (count == 1) {
    const int k = m[0] != kNoSplit ? 0 : m[1] != kNoSplit ? 1 : 2;
    out.push_back({c[k], m[k], c[(k + 2) % 3]});
    out.push_back({m[k], c[(k + 1) % 3], c[(k + 2) % 3]});
  } else if (count == 2) {
    const int k = m[2] == kNoSplit ? 0 : m[0] == kNoSplit ? 1 : 2;  // edges k, k+1 split
    const std::uint32_t a = c[k], b = c[(k + 1) % 3], d = c[(k + 2) % 3];
    const std::uint32_t mk = m[k], ml = m[(k + 1) % 3];
    out.push_back({mk, b, ml});
    // The quad a, mk, ml, d along its shorter diagonal; mk–ml (the ridge) stays.
    if ((v[a] - v[ml]).squaredNorm() <= (v[mk] - v[d]).squaredNorm()) {
      out.push_back({a, mk, ml});
      out.push_back({a, ml, d});
    } else {
      out.push_back({a, mk, d});
      out.push_back({mk, ml, d});
    }
  } else {
    out.push_back({c[0], m[0], m[2]});
    out.push_back({m[0], c[1], m[1]});
    out.push_back({m[2], m[1], c[2]});
    out.push_back({m[0], m[1], m[2]});
  }
}

}  // namespace

offline::TriangleMesh DexelModel::machined_mesh() const {
  offline::TriangleMesh mesh;
  // A line holds a surface point when its height lies strictly inside
  // (floor, stock cap). Cut through to the floor, the material is gone from
  // the whole line (the neighbouring face of a convex edge went deeper); at
  // the cap, material continues beyond it (the neighbouring face of a
  // concave edge is oversize). Such a vertex p + h·n is no point of the
  // machined surface (a spike the CMM would probe): a dexel on a sharp edge
  // takes the vertex of a partner on the other face that has a surface point
  // (the corner where the machined faces meet), and from there the vertex
  // spreads to the mesh neighbours without one (a gouge or oversize wider
  // than the dexel spacing) while it lies within max_depth_mm of their line.
  const std::size_t nd = position_.size();
  auto on_line = [&](std::size_t i) {
    return line_[i].height > floor_[i] && line_[i].height < options_.max_stock_mm;
  };
  std::vector<Eigen::Vector3d> vertex(nd);
  std::vector<char> placed(nd, 0);
  std::vector<std::uint32_t> queue;
  for (std::size_t i = 0; i < nd; ++i) {
    vertex[i] = position_[i] + line_[i].height * normal_[i];
    if (on_line(i)) {
      placed[i] = 1;
      continue;
    }
    for (std::size_t j = partner_[i]; j != i; j = partner_[j])
      if (on_line(j)) {
        vertex[i] = position_[j] + line_[j].height * normal_[j];
        placed[i] = 1;
        queue.push_back(static_cast<std::uint32_t>(i));
        break;
      }
  }
  bool any_unplaced = false;
  for (std::size_t i = 0; i < nd; ++i)
    any_unplaced = any_unplaced || !placed[i];
  if (any_unplaced) {
    std::vector<std::uint32_t> start(nd + 1, 0), items(3 * 2 * triangles_.size());
    for (const auto& t : triangles_)
      for (auto v : t)
        start[v + 1] += 2;
    for (std::size_t i = 0; i < nd; ++i)
      start[i + 1] += start[i];
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (const auto& t : triangles_)
      for (int k = 0; k < 3; ++k) {
        items[fill[t[k]]++] = t[(k + 1) % 3];
        items[fill[t[k]]++] = t[(k + 2) % 3];
      }
    // Spreads placed vertices to unplaced neighbours (cut through only, or
    // any) while they lie within max_depth_mm of the neighbour's line.
    auto spread = [&](bool cut_through_only) {
      for (std::size_t q = 0; q < queue.size(); ++q) {
        const std::uint32_t from = queue[q];
        for (std::uint32_t k = start[from]; k < start[from + 1]; ++k) {
          const std::uint32_t d = items[k];
          if (placed[d] || (cut_through_only && line_[d].height > floor_[d])) continue;
          const Eigen::Vector3d off = vertex[from] - position_[d];
          if ((off - off.dot(normal_[d]) * normal_[d]).norm() > options_.max_depth_mm) continue;
          vertex[d] = vertex[from];
          placed[d] = 1;
          queue.push_back(d);
        }
      }
    };
    spread(false);
    // Edge dexels cut through on both sides (a convex edge with both faces
    // below nominal) have no partner to take: they take a neighbour's vertex
    // on their own face (the edge is rounded off by one dexel spacing).
    queue.clear();
    for (std::size_t i = 0; i < nd; ++i)
      if (placed[i]) queue.push_back(static_cast<std::uint32_t>(i));
    spread(true);
  }
  mesh.vertices_mm = std::move(vertex);

  // Cusps. Between two dexels left by different passes the machined surface
  // rises to a cusp that a straight edge cuts off (by up to the cusp's slope
  // × half the dexel spacing: 17 µm for a Ø6 ball at 1 mm stepover and
  // 0.3 mm dexels). Each dexel knows the surface its last instance swept (a
  // ball's tube, a flank's or flat bottom's plane); the cusp lies where the
  // two surfaces of an edge's dexels meet: that point is added to the edge
  // (shared by both triangles of the edge) when it stands above the
  // straight edge, and no other neighbouring surface passes below it.
  auto swept = [&](std::size_t i) {
    SweptSurface s;
    s.kind = sweep_kind_[i];
    s.point = position_[i] + sweep_point_[i].cast<double>();
    s.vector = sweep_vector_[i].cast<double>();
    if (s.vector.squaredNorm() > 0) s.vector.normalize();
    s.radius = sweep_radius_[i];
    return s;
  };
  // An edge can hold a cusp when both dexels carry a swept surface and the
  // two differ (the dexels of one flat face or of one straight pass share
  // theirs: nothing to intersect, and most edges are skipped here).
  auto candidate = [&](std::uint32_t a, std::uint32_t b) {
    if (sweep_kind_[a] == kSweptNone || sweep_kind_[b] == kSweptNone || !on_line(a) || !on_line(b))
      return false;
    if (sweep_kind_[a] != sweep_kind_[b]) return true;
    const SweptSurface sa = swept(a), sb = swept(b);
    constexpr double kSame = 2e-6;  // mm (the offsets are stored as float)
    const Eigen::Vector3d d = sb.point - sa.point;
    if (sa.kind == kSweptPlane)
      return (sa.vector - sb.vector).norm() > 1e-5 || std::abs(sa.vector.dot(d)) > kSame;
    if (std::abs(sa.radius - sb.radius) > kSame) return true;
    if (sa.vector.squaredNorm() == 0 || sb.vector.squaredNorm() == 0) return d.norm() > kSame;
    return sa.vector.cross(sb.vector).norm() > 1e-5 ||
           (d - d.dot(sa.vector) * sa.vector).norm() > kSame;
  };
  // fn(begin, end) over [0, n) in chunks of `per_chunk`, on the model's
  // cutting threads when it has several; each chunk writes only its own
  // items, so the result is the same for any number of threads.
  detail::WorkerPool* pool = threads_.get();
  auto in_chunks = [&](std::size_t n, std::size_t per_chunk, auto&& fn) {
    const auto chunks = static_cast<std::uint32_t>((n + per_chunk - 1) / per_chunk);
    auto run_chunk = [&](std::uint32_t c) {
      fn(std::size_t(c) * per_chunk, std::min(n, std::size_t(c + 1) * per_chunk));
    };
    if (pool != nullptr && pool->threads() > 1 && chunks > 1) {
      pool->run(
          chunks,
          [](void* context, std::uint32_t c, int) {
            (*static_cast<decltype(run_chunk)*>(context))(c);
          },
          &run_chunk);
    } else {
      for (std::uint32_t c = 0; c < chunks; ++c)
        run_chunk(c);
    }
  };
  // The candidate edges, each once, in the order the triangles meet them
  // (edge k of a triangle runs from its corner k to k + 1), with the
  // vertices opposite each (one or two triangles); per triangle edge, its
  // candidate's index or kNoSplit.
  struct Candidate {
    std::uint32_t a, b;  // a < b
    std::array<std::uint32_t, 2> opposite{kNoSplit, kNoSplit};
  };
  std::vector<Candidate> candidates;
  std::vector<std::uint32_t> edge_candidate(3 * triangles_.size(), kNoSplit);
  {
    // Site s = 3·triangle + k. An edge's sites are found among those of its
    // lower vertex (a handful each), grouped by a counting sort that keeps
    // the site order: no hash table (which was two thirds of the serial
    // part of this function on benchmark004).
    const std::size_t sites = edge_candidate.size();
    auto corner = [&](std::size_t site, int step) {
      return triangles_[site / 3][(site % 3 + step) % 3];
    };
    auto low = [&](std::size_t site) { return std::min(corner(site, 0), corner(site, 1)); };
    auto high = [&](std::size_t site) { return std::max(corner(site, 0), corner(site, 1)); };
    std::vector<char> is_site(sites, 0);
    in_chunks(sites, 16384, [&](std::size_t begin, std::size_t end) {
      for (std::size_t site = begin; site < end; ++site)
        is_site[site] = candidate(corner(site, 0), corner(site, 1));
    });
    std::vector<std::uint32_t> group_start(nd + 1, 0);
    for (std::size_t site = 0; site < sites; ++site)
      if (is_site[site]) ++group_start[low(site) + 1];
    for (std::size_t v = 0; v < nd; ++v)
      group_start[v + 1] += group_start[v];
    std::vector<std::uint32_t> grouped(group_start[nd]);
    {
      std::vector<std::uint32_t> fill(group_start.begin(), group_start.end() - 1);
      for (std::size_t site = 0; site < sites; ++site)
        if (is_site[site]) grouped[fill[low(site)]++] = static_cast<std::uint32_t>(site);
    }
    // The first site of each site's edge (the site itself when it is first).
    std::vector<std::uint32_t> first_site(sites, kNoSplit);
    for (std::size_t v = 0; v < nd; ++v)
      for (std::uint32_t i = group_start[v]; i < group_start[v + 1]; ++i) {
        const std::uint32_t site = grouped[i];
        first_site[site] = site;
        for (std::uint32_t j = group_start[v]; j < i; ++j)
          if (high(grouped[j]) == high(site)) {
            first_site[site] = first_site[grouped[j]];
            break;
          }
      }
    for (std::size_t site = 0; site < sites; ++site) {
      if (!is_site[site]) continue;
      const bool first = first_site[site] == site;
      if (first) {
        edge_candidate[site] = static_cast<std::uint32_t>(candidates.size());
        candidates.push_back({low(site), high(site)});
      } else {
        edge_candidate[site] = edge_candidate[first_site[site]];
      }
      candidates[edge_candidate[site]].opposite[first ? 0 : 1] = corner(site, 2);
    }
  }
  // The cusp of a candidate edge (a < b), if it has one.
  auto find_cusp = [&](const Candidate& edge, Eigen::Vector3d& cusp_mm) -> bool {
    const std::uint32_t a = edge.a, b = edge.b;
    const SweptSurface sa = swept(a), sb = swept(b);
    const Eigen::Vector3d pa = position_[a], dp = position_[b] - position_[a];
    auto line_at = [&](double s, Eigen::Vector3d& n) {
      n = ((1 - s) * normal_[a] + s * normal_[b]).normalized();
      return Eigen::Vector3d(pa + s * dp);
    };
    auto heights = [&](double s, double& ha, double& hb) {
      Eigen::Vector3d n;
      const Eigen::Vector3d x = line_at(s, n);
      ha = entry(sa, x, n);
      hb = entry(sb, x, n);
    };
    // Each surface must reproduce its own dexel (to 0.5 µm) and lie above
    // the other's dexel: a's surface is the lower one near a, b's near b.
    double ha0, hb0, ha1, hb1;
    heights(0, ha0, hb0);
    heights(1, ha1, hb1);
    constexpr double kAgree = 5e-4;
    if (!(std::abs(ha0 - line_[a].height) < kAgree && std::abs(hb1 - line_[b].height) < kAgree &&
          hb0 > ha0 + 1e-6 && ha1 > hb1 + 1e-6))
      return false;
    double lo = 0, hi = 1;
    for (int it = 0; it < 48; ++it) {
      const double mid = 0.5 * (lo + hi);
      double ha, hb;
      heights(mid, ha, hb);
      (ha < hb ? lo : hi) = mid;
    }
    const double s = 0.5 * (lo + hi);
    if (s < 0.05 || s > 0.95) return false;
    double ha, hb;
    heights(s, ha, hb);
    Eigen::Vector3d n;
    const Eigen::Vector3d x = line_at(s, n);
    // Any other surface near the edge (of the vertices opposite it) that
    // passes lower bounds the cusp too.
    double ridge = std::min(ha, hb);
    for (const std::uint32_t c : edge.opposite)
      if (c != kNoSplit && sweep_kind_[c] != kSweptNone && on_line(c))
        ridge = std::min(ridge, entry(swept(c), x, n));
    const double straight = (1 - s) * line_[a].height + s * line_[b].height;
    // Cusps lower than this are left to the straight edge (the creases
    // between the flanks of neighbouring instances of a deflected tool would
    // otherwise add vertices all over the walls).
    constexpr double kMinRise = 5e-4;
    if (!(ridge > straight + kMinRise && ridge < straight + 0.5 * dp.norm() &&
          ridge < options_.max_stock_mm))
      return false;
    cusp_mm = x + ridge * n;
    return true;
  };
  // The bisections are independent: the model's cutting threads share them
  // (half of the free-form's machined_mesh() on one thread), and the cusp
  // vertices are then numbered in the candidates' order, whichever thread
  // found them: the mesh is the same for any number of threads.
  std::vector<Eigen::Vector3d> cusp_point(candidates.size());
  std::vector<char> has_cusp(candidates.size(), 0);
  in_chunks(candidates.size(), 1024, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      has_cusp[i] = find_cusp(candidates[i], cusp_point[i]);
  });
  std::vector<std::uint32_t> cusp_vertex(candidates.size(), kNoSplit);
  for (std::size_t i = 0; i < candidates.size(); ++i)
    if (has_cusp[i]) {
      cusp_vertex[i] = static_cast<std::uint32_t>(mesh.vertices_mm.size());
      mesh.vertices_mm.push_back(cusp_point[i]);
    }
  auto cusp = [&](std::size_t t, int k) -> std::uint32_t {
    const std::uint32_t c = edge_candidate[3 * t + k];
    return c == kNoSplit ? kNoSplit : cusp_vertex[c];
  };

  // Relocated vertices can collapse a triangle; readers reject those (STL
  // stores float), so drop the ones that are degenerate in float.
  mesh.triangles.reserve(triangles_.size());
  std::vector<offline::Triangle> pieces;
  for (std::size_t ti = 0; ti < triangles_.size(); ++ti) {
    const auto& t = triangles_[ti];
    const std::uint32_t c[3] = {t[0], t[1], t[2]};
    const std::uint32_t m[3] = {cusp(ti, 0), cusp(ti, 1), cusp(ti, 2)};
    pieces.clear();
    emit_split(c, m, mesh.vertices_mm, pieces);
    const bool own = placed[t[0]] + placed[t[1]] + placed[t[2]] == 3 && on_line(t[0]) &&
                     on_line(t[1]) && on_line(t[2]);
    for (const auto& piece : pieces) {
      if (own && m[0] == kNoSplit && m[1] == kNoSplit && m[2] == kNoSplit) {
        mesh.triangles.push_back(piece);
        continue;
      }
      const Eigen::Vector3d a = mesh.vertices_mm[piece[0]].cast<float>().cast<double>();
      const Eigen::Vector3d ab = mesh.vertices_mm[piece[1]].cast<float>().cast<double>() - a;
      const Eigen::Vector3d ac = mesh.vertices_mm[piece[2]].cast<float>().cast<double>() - a;
      const double longest_sq =
          std::max({ab.squaredNorm(), ac.squaredNorm(), (ac - ab).squaredNorm()});
      if (ab.cross(ac).norm() > 1e-9 * longest_sq) mesh.triangles.push_back(piece);
    }
  }
  const auto base = static_cast<std::uint32_t>(mesh.vertices_mm.size());
  mesh.vertices_mm.insert(mesh.vertices_mm.end(), fixed_vertices_.begin(), fixed_vertices_.end());
  for (const auto& t : fixed_triangles_)
    mesh.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  return mesh;
}

void DexelModel::write_machined(const std::filesystem::path& dir,
                                const std::string& comment) const {
  const offline::TriangleMesh mesh = machined_mesh();
  const std::string text =
      comment.empty() ? std::string("truecut machined surface, workpiece frame, mm") : comment;
  offline::write_stl(dir / kMachinedStl, mesh, offline::StlEncoding::kBinary, text.substr(0, 80));
  offline::write_ply(dir / kMachinedPly, mesh, offline::PlyEncoding::kBinaryLittleEndian, text);
}

double DexelModel::removed_total_mm3() const {
  double sum = 0;
  for (std::size_t i = 0; i < line_.size(); ++i)
    sum += (initial_height_[i] - line_[i].height) * area_[i];
  return sum;
}

}  // namespace truecut::sim::cutting
