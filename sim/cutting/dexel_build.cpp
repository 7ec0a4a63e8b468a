// DexelModel::build: samples the nominal surfaces, sets the initial heights
// from the stock and bins the dexel lines into the uniform grid.
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdio>
#include <limits>
#include <span>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <Eigen/Geometry>

#include "truecut/sim/cutting/dexel_model.hpp"

namespace truecut::sim::cutting {

namespace {

// A grid entry's group in its cell: 0 for all three first-cell flags (the
// dexel's box starts in the cell), then XY, XZ, X, YZ, Y, Z, none.
int flag_group(std::uint32_t entry) {
  return static_cast<int>((~entry) >> 29);
}

constexpr std::uint32_t kNone = 0xFFFFFFFFu;

// Unit directions into the face from the sharp edges a dexel lies on.
struct EdgeInsets {
  Eigen::Vector3d dir[2];
  int count = 0;
  double inset_mm = 0;
};
constexpr double kSmoothCos = 0.8660254037844387;  // faces within 30° share vertex normals
constexpr double kWeldCos = 0.9999;                // coincident dexels merge below ~0.8°

// Key of a dexel position for welding: surface id and the exact coordinates.
struct WeldKey {
  int surface;
  std::uint64_t bits[3];
  bool operator==(const WeldKey&) const = default;
};
struct WeldHash {
  std::size_t operator()(const WeldKey& k) const {
    std::uint64_t h = std::uint64_t(k.surface) * 0x9E3779B97F4A7C15ull;
    for (auto b : k.bits)
      h = (h ^ b) * 0x100000001B3ull + (h >> 29);
    h ^= h >> 31;  // the low bits index the table: fold the high bits in
    h *= 0xBF58476D1CE4E5B9ull;
    return h ^ (h >> 27);
  }
};

// WeldKey -> dexel index with open addressing (linear probing, power-of-two
// size, at most half full). A slot holds only the index of the newest
// dexel at its key (4 bytes: the table of a million dexels stays in a few
// MB of cache); the key is that dexel's own, read back through `key_of`.
// One lookup per sub-vertex of every triangle is most of building a model.
template <class KeyOf>
class WeldTable {
 public:
  WeldTable(std::size_t expected, KeyOf key_of) : key_of_(key_of) {
    slots_.assign(std::bit_ceil(std::max<std::size_t>(16, 2 * expected)), kNone);
  }
  // The slot of `key`: the one holding it, or the empty one where it goes.
  std::size_t find(const WeldKey& key) const {
    std::size_t i = WeldHash{}(key) & (slots_.size() - 1);
    while (slots_[i] != kNone && !(key_of_(slots_[i]) == key))
      i = (i + 1) & (slots_.size() - 1);
    return i;
  }
  std::uint32_t value(std::size_t slot) const { return slots_[slot]; }
  // Stores `dexel` (whose key is the slot's) at a slot find() returned; the
  // slot may move when the table grows, so look it up again afterwards.
  void set(std::size_t slot, std::uint32_t dexel) {
    if (slots_[slot] == kNone) ++size_;
    slots_[slot] = dexel;
    if (2 * size_ > slots_.size()) grow();
  }

 private:
  void grow() {
    std::vector<std::uint32_t> old(2 * slots_.size(), kNone);
    old.swap(slots_);
    for (std::uint32_t v : old)
      if (v != kNone) slots_[find(key_of_(v))] = v;
  }
  KeyOf key_of_;
  std::vector<std::uint32_t> slots_;
  std::size_t size_ = 0;
};

WeldKey weld_key(int surface, const Eigen::Vector3d& p) {
  WeldKey k{surface, {}};
  for (int i = 0; i < 3; ++i)
    k.bits[i] = std::bit_cast<std::uint64_t>(p[i] == 0 ? 0.0 : p[i]);  // −0 → +0
  return k;
}

// The longest edge of triangle t, and the pieces each edge is cut into so
// that none is longer than the dexel spacing.
template <class Vertices, class Triangle>
double longest_edge_mm(const Vertices& V, const Triangle& t) {
  return std::max(
      {(V[t[1]] - V[t[0]]).norm(), (V[t[2]] - V[t[1]]).norm(), (V[t[0]] - V[t[2]]).norm()});
}
template <class Vertices, class Triangle>
int pieces_per_edge(const Vertices& V, const Triangle& t, double spacing_mm) {
  return std::max(1, static_cast<int>(std::ceil(longest_edge_mm(V, t) / spacing_mm - 1e-9)));
}

constexpr double kStockEps = 1e-9;  // a point this close to a box is in it

// The stock boxes that may hold a point, by a uniform grid over their union
// (a part's stock can be hundreds of boxes: benchmark004 has 384). A cell
// lists, in the stock's order, every box whose slightly grown extent meets
// it, so the first box of a point's cell that holds the point is the first
// of all the boxes that does.
class StockGrid {
 public:
  explicit StockGrid(std::span<const StockBox> stock) : stock_(stock) {
    if (stock.empty()) return;
    lo_ = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector3d hi = -lo_;
    for (const StockBox& b : stock) {
      lo_ = lo_.cwiseMin((b.min_mm.array() - kStockEps).matrix());
      hi = hi.cwiseMax((b.max_mm.array() + kStockEps).matrix());
    }
    if (!lo_.allFinite() || !hi.allFinite()) return;  // every query scans them all
    const int per_axis = std::clamp(static_cast<int>(std::cbrt(8.0 * double(stock.size()))), 1, 64);
    for (int i = 0; i < 3; ++i) {
      dims_[i] = per_axis;
      cell_mm_[i] = std::max((hi[i] - lo_[i]) / per_axis, 1e-9);
    }
    hi_ = hi;
    std::vector<std::vector<std::uint32_t>> lists(std::size_t(dims_[0]) * dims_[1] * dims_[2]);
    for (std::size_t k = 0; k < stock.size(); ++k) {
      const auto a = cell_of((stock[k].min_mm.array() - kStockEps).matrix());
      const auto b = cell_of((stock[k].max_mm.array() + kStockEps).matrix());
      for (int z = a[2]; z <= b[2]; ++z)
        for (int y = a[1]; y <= b[1]; ++y)
          for (int x = a[0]; x <= b[0]; ++x)
            lists[index(x, y, z)].push_back(static_cast<std::uint32_t>(k));
    }
    start_.assign(lists.size() + 1, 0);
    for (std::size_t c = 0; c < lists.size(); ++c) {
      start_[c + 1] = start_[c] + static_cast<std::uint32_t>(lists[c].size());
      boxes_.insert(boxes_.end(), lists[c].begin(), lists[c].end());
    }
    indexed_ = true;
  }

  std::size_t size() const { return stock_.size(); }
  // Calls f(box) for the boxes that may hold x, in the stock's order, until f
  // returns true.
  template <class F>
  void visit(const Eigen::Vector3d& x, F&& f) const {
    if (!indexed_ || !x.allFinite()) {
      for (const StockBox& b : stock_)
        if (f(b)) return;
      return;
    }
    if ((x.array() < lo_.array()).any() || (x.array() > hi_.array()).any()) return;
    const auto c = cell_of(x);
    const std::size_t cell = index(c[0], c[1], c[2]);
    for (std::uint32_t i = start_[cell]; i < start_[cell + 1]; ++i)
      if (f(stock_[boxes_[i]])) return;
  }

 private:
  std::array<int, 3> cell_of(const Eigen::Vector3d& p) const {
    std::array<int, 3> c{};
    for (int i = 0; i < 3; ++i)
      c[i] =
          std::clamp(static_cast<int>(std::floor((p[i] - lo_[i]) / cell_mm_[i])), 0, dims_[i] - 1);
    return c;
  }
  std::size_t index(int x, int y, int z) const {
    return (std::size_t(z) * dims_[1] + y) * dims_[0] + x;
  }

  std::span<const StockBox> stock_;
  bool indexed_ = false;
  Eigen::Vector3d lo_ = Eigen::Vector3d::Zero(), hi_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d cell_mm_ = Eigen::Vector3d::Ones();
  std::array<int, 3> dims_{1, 1, 1};
  std::vector<std::uint32_t> start_, boxes_;
};

// Distance from p along n to where the union of boxes ends (0 when p is not
// inside any box), capped at `cap`.
double stock_height(const Eigen::Vector3d& p, const Eigen::Vector3d& n, const StockGrid& grid,
                    double cap) {
  constexpr double kEps = kStockEps;
  double t = 0;
  for (std::size_t pass = 0; pass <= grid.size() && t < cap; ++pass) {
    bool advanced = false;
    const Eigen::Vector3d x = p + t * n;
    grid.visit(x, [&](const StockBox& b) {
      if ((x.array() < b.min_mm.array() - kEps).any() ||
          (x.array() > b.max_mm.array() + kEps).any())
        return false;
      double exit = std::numeric_limits<double>::infinity();
      for (int i = 0; i < 3; ++i) {
        if (n[i] > 1e-15) exit = std::min(exit, (b.max_mm[i] - x[i]) / n[i]);
        if (n[i] < -1e-15) exit = std::min(exit, (b.min_mm[i] - x[i]) / n[i]);
      }
      if (exit > 1e-12) {
        t += exit;
        advanced = true;
        return true;
      }
      return false;
    });
    if (!advanced) break;
  }
  return std::clamp(t, 0.0, cap);
}

void check_options(const DexelOptions& o) {
  auto positive = [](double v, const char* name, double min) {
    if (!std::isfinite(v) || v < min)
      throw std::invalid_argument(std::string("DexelOptions::") + name + " must be >= " +
                                  std::to_string(min) + " (got " + std::to_string(v) + ")");
  };
  positive(o.spacing_mm, "spacing_mm", 1e-4);
  positive(o.max_stock_mm, "max_stock_mm", 0);
  positive(o.max_depth_mm, "max_depth_mm", 0);
  positive(o.tolerance_mm, "tolerance_mm", 1e-6);
  positive(o.cell_mm, "cell_mm", 0);
  if (o.max_substeps < 1) throw std::invalid_argument("DexelOptions::max_substeps must be >= 1");
  if (o.max_dexels < 1 || o.max_dexels > kMaxDexels)
    throw std::invalid_argument("DexelOptions::max_dexels must be 1 .. " +
                                std::to_string(kMaxDexels));
  if (o.threads < 0 || o.threads > 256)
    throw std::invalid_argument("DexelOptions::threads must be 0 (one per hardware thread) .. 256");
}

// Refuses a model of more dexels than options.max_dexels before any is made.
void check_dexel_budget(double expected_dexels, const DexelOptions& o) {
  if (expected_dexels <= static_cast<double>(o.max_dexels)) return;
  char text[512];
  std::snprintf(text, sizeof text,
                "cutting: the nominal at a dexel spacing of %g mm would make about %.3g dexels "
                "(about %.3g GB), more than max-dexels %zu; check the nominal's unit (mm), raise "
                "the spacing (--dexel-spacing) or the limit (--max-dexels, at most %zu)",
                o.spacing_mm, expected_dexels, expected_dexels * double(kBytesPerDexel) * 1e-9,
                o.max_dexels, kMaxDexels);
  throw std::length_error(text);
}

}  // namespace

DexelModel DexelModel::build(const offline::TriangleMesh& nominal,
                             std::span<const int> triangle_surface, std::span<const StockBox> stock,
                             const DexelOptions& options) {
  check_options(options);
  if (triangle_surface.size() != nominal.triangles.size())
    throw std::invalid_argument("cutting: " + std::to_string(triangle_surface.size()) +
                                " surface ids for " + std::to_string(nominal.triangles.size()) +
                                " triangles");
  DexelModel m;
  m.options_ = options;
  auto modelled = [&](int surface) {
    return options.surfaces.empty() || std::find(options.surfaces.begin(), options.surfaces.end(),
                                                 surface) != options.surfaces.end();
  };
  const auto& V = nominal.vertices_mm;
  const std::size_t nt = nominal.triangles.size();
  for (const auto& t : nominal.triangles)
    for (auto v : t)
      if (v >= V.size()) throw std::invalid_argument("cutting: triangle index out of range");

  // Face normals and areas; faces around each vertex (CSR).
  std::vector<Eigen::Vector3d> face_n(nt);
  std::vector<double> face_area(nt);
  std::vector<std::uint32_t> vstart(V.size() + 1, 0), vfaces(3 * nt);
  for (std::size_t f = 0; f < nt; ++f) {
    const auto& t = nominal.triangles[f];
    const Eigen::Vector3d c = (V[t[1]] - V[t[0]]).cross(V[t[2]] - V[t[0]]);
    face_area[f] = 0.5 * c.norm();
    face_n[f] = face_area[f] > 0 ? Eigen::Vector3d(c / c.norm()) : Eigen::Vector3d::Zero();
    for (auto v : t)
      ++vstart[v + 1];
  }
  for (std::size_t v = 0; v < V.size(); ++v)
    vstart[v + 1] += vstart[v];
  {
    std::vector<std::uint32_t> fill(vstart.begin(), vstart.end() - 1);
    for (std::size_t f = 0; f < nt; ++f)
      for (auto v : nominal.triangles[f])
        vfaces[fill[v]++] = static_cast<std::uint32_t>(f);
  }
  // Normal of face f's corner at vertex v: area-weighted over the faces of
  // the same surface at v that lie within 30° of f (sharp edges stay sharp).
  auto corner_normal = [&](std::size_t f, std::uint32_t v) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (std::uint32_t i = vstart[v]; i < vstart[v + 1]; ++i) {
      const std::uint32_t g = vfaces[i];
      if (triangle_surface[g] == triangle_surface[f] && face_n[g].dot(face_n[f]) > kSmoothCos)
        sum += face_area[g] * face_n[g];
    }
    return Eigen::Vector3d(sum.normalized());
  };

  // Is the edge (a, b) of face f sharp: no smooth neighbour of the same surface?
  auto sharp_edge = [&](std::size_t f, std::uint32_t a, std::uint32_t b) {
    bool smooth = false;
    for (std::uint32_t i = vstart[a]; i < vstart[a + 1]; ++i) {
      const std::uint32_t g = vfaces[i];
      const auto& tg = nominal.triangles[g];
      if (g == f || (tg[0] != b && tg[1] != b && tg[2] != b)) continue;
      if (triangle_surface[g] != triangle_surface[f] || face_n[g].dot(face_n[f]) <= kSmoothCos)
        return true;
      smooth = true;
    }
    return !smooth;
  };

  // The dexels at one weld key, newest first: the head in `welded`, the rest
  // through `next_welded` (one map entry per position, no list per entry).
  // Sized for the dexels to come, so it is not rehashed while it fills: a
  // triangle cut into n² sub-triangles has (n-1)(n-2)/2 points of its own,
  // 3(n-1) on edges shared with a neighbour and 3 corners shared by about six.
  double expected_dexels = 0;
  for (std::size_t f = 0; f < nt; ++f) {
    if (!modelled(triangle_surface[f]) || face_area[f] <= 0) continue;
    const double n = pieces_per_edge(V, nominal.triangles[f], options.spacing_mm);
    expected_dexels += (n - 1) * (n - 2) / 2 + 1.5 * (n - 1) + 0.5;
  }
  check_dexel_budget(expected_dexels, options);
  // (Capped: an estimate is not worth gigabytes; past it the table grows.)
  auto dexel_key = [&m](std::uint32_t i) { return weld_key(m.surface_[i], m.position_[i]); };
  WeldTable welded(static_cast<std::size_t>(std::min(expected_dexels, 16e6)) + 16, dexel_key);
  std::vector<std::uint32_t> next_welded;
  // Inset directions gathered from every triangle that shares a dexel (a
  // block corner is on the sharp edges of two triangles); applied at the end.
  std::vector<EdgeInsets> insets;
  auto dexel = [&](int surface, const Eigen::Vector3d& p, const Eigen::Vector3d& n,
                   const EdgeInsets& in) {
    const WeldKey key = weld_key(surface, p);
    const std::size_t slot = welded.find(key);
    const std::uint32_t head = welded.value(slot);
    std::uint32_t index = kNone;
    for (std::uint32_t i = head; i != kNone && index == kNone; i = next_welded[i])
      if (m.normal_[i].dot(n) > kWeldCos) index = i;  // the newest that matches
    if (index == kNone) {
      if (m.position_.size() >= kMaxDexels)
        throw std::length_error("cutting: more than 50 million dexels; raise spacing_mm");
      index = static_cast<std::uint32_t>(m.position_.size());
      m.position_.push_back(p);
      m.normal_.push_back(n);
      m.area_.push_back(0);
      m.surface_.push_back(surface);
      next_welded.push_back(head);
      welded.set(slot, index);
      insets.emplace_back();
    }
    if (in.count > 0) {
      EdgeInsets& acc = insets[index];
      for (int k = 0; k < in.count; ++k) {
        bool known = false;
        for (int q = 0; q < acc.count; ++q)
          known = known || acc.dir[q].dot(in.dir[k]) > 0.99;
        if (!known && acc.count < 2) acc.dir[acc.count++] = in.dir[k];
      }
      acc.inset_mm = acc.inset_mm > 0 ? std::min(acc.inset_mm, in.inset_mm) : in.inset_mm;
    }
    return index;
  };

  std::vector<std::uint32_t> local;  // dexel of each sub-vertex of the current triangle
  for (std::size_t f = 0; f < nt; ++f) {
    const auto& t = nominal.triangles[f];
    const int surface = triangle_surface[f];
    if (!modelled(surface)) {
      const auto base = static_cast<std::uint32_t>(m.fixed_vertices_.size());
      for (auto v : t)
        m.fixed_vertices_.push_back(V[v]);
      m.fixed_triangles_.push_back({base, base + 1, base + 2});
      continue;
    }
    if (face_area[f] <= 0) continue;  // degenerate: no surface to sample
    const double longest = longest_edge_mm(V, t);
    const int n = pieces_per_edge(V, t, options.spacing_mm);
    const Eigen::Vector3d cn[3] = {corner_normal(f, t[0]), corner_normal(f, t[1]),
                                   corner_normal(f, t[2])};
    // Dexels on a sharp edge test their line a quarter sub-triangle inside
    // the face: a tool flush with the neighbouring face must not catch them.
    const double heights[3] = {2 * face_area[f] / (V[t[2]] - V[t[1]]).norm(),
                               2 * face_area[f] / (V[t[2]] - V[t[0]]).norm(),
                               2 * face_area[f] / (V[t[1]] - V[t[0]]).norm()};
    const double inset = 0.25 * std::min(longest / n, *std::min_element(heights, heights + 3));
    auto inward = [&](int a, int b, int c) {
      if (!sharp_edge(f, t[a], t[b])) return Eigen::Vector3d(Eigen::Vector3d::Zero());
      const Eigen::Vector3d d = (V[t[b]] - V[t[a]]).normalized();
      Eigen::Vector3d in = V[t[c]] - V[t[a]];
      in -= in.dot(d) * d;
      return Eigen::Vector3d(in.normalized());
    };
    const Eigen::Vector3d in01 = inward(0, 1, 2), in02 = inward(0, 2, 1), in12 = inward(1, 2, 0);
    auto origin = [&](int i, int j, const Eigen::Vector3d&) {
      EdgeInsets e;
      e.inset_mm = inset;
      for (const auto& [on, dir] :
           {std::pair{j == 0, &in01}, std::pair{i == 0, &in02}, std::pair{i + j == n, &in12}})
        if (on && dir->squaredNorm() > 0 && e.count < 2) e.dir[e.count++] = *dir;
      return e;
    };
    // Edge points from the lower vertex index, so both triangles of an edge
    // compute bit-identical points and normals (and weld).
    auto edge = [&](int a, int b, int k, int i, int j) {
      if (t[a] > t[b]) {
        std::swap(a, b);
        k = n - k;
      }
      const double s = double(k) / n;
      const Eigen::Vector3d p = V[t[a]] + s * (V[t[b]] - V[t[a]]);
      const Eigen::Vector3d nn = ((1 - s) * cn[a] + s * cn[b]).normalized();
      return dexel(surface, p, nn, origin(i, j, p));
    };
    auto at = [&](int i, int j) { return std::size_t(j) * (n + 1) + i; };
    local.assign(std::size_t(n + 1) * (n + 1), 0);
    for (int j = 0; j <= n; ++j) {
      for (int i = 0; i + j <= n; ++i) {
        std::uint32_t d;
        if (i == 0 && j == 0)
          d = dexel(surface, V[t[0]], cn[0], origin(i, j, V[t[0]]));
        else if (i == n)
          d = dexel(surface, V[t[1]], cn[1], origin(i, j, V[t[1]]));
        else if (j == n)
          d = dexel(surface, V[t[2]], cn[2], origin(i, j, V[t[2]]));
        else if (j == 0)
          d = edge(0, 1, i, i, j);
        else if (i == 0)
          d = edge(0, 2, j, i, j);
        else if (i + j == n)
          d = edge(1, 2, j, i, j);
        else {
          const double u = double(i) / n, v = double(j) / n, w = 1 - u - v;
          const Eigen::Vector3d p = w * V[t[0]] + u * V[t[1]] + v * V[t[2]];
          const Eigen::Vector3d nn = (w * cn[0] + u * cn[1] + v * cn[2]).normalized();
          d = dexel(surface, p, nn, EdgeInsets{});
        }
        local[at(i, j)] = d;
      }
    }
    const double third = face_area[f] / (double(n) * n) / 3;
    auto add = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
      m.triangles_.push_back({a, b, c});
      m.area_[a] += third;
      m.area_[b] += third;
      m.area_[c] += third;
    };
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i + j < n; ++i) {
        add(local[at(i, j)], local[at(i + 1, j)], local[at(i, j + 1)]);
        if (i + j + 2 <= n) add(local[at(i + 1, j)], local[at(i + 1, j + 1)], local[at(i, j + 1)]);
      }
    }
  }

  const std::size_t nd = m.position_.size();
  m.line_origin_ = m.position_;
  for (std::size_t i = 0; i < nd; ++i)
    for (int k = 0; k < insets[i].count; ++k)
      m.line_origin_[i] += insets[i].inset_mm * insets[i].dir[k];
  m.initial_height_.resize(nd);
  m.floor_.assign(nd, -options.max_depth_mm);
  const StockGrid stock_grid(stock);
  for (std::size_t i = 0; i < nd; ++i)
    m.initial_height_[i] =
        stock_height(m.line_origin_[i], m.normal_[i], stock_grid, options.max_stock_mm);
  // Partners: the dexels at one position with different normals (the
  // sides of a sharp edge or corner), linked in a cycle.
  m.partner_.resize(nd);
  {
    WeldTable first(nd, [&m](std::uint32_t i) { return weld_key(0, m.position_[i]); });
    std::vector<std::uint32_t> last(nd);
    for (std::size_t i = 0; i < nd; ++i) {
      m.partner_[i] = last[i] = static_cast<std::uint32_t>(i);
      const std::size_t slot = first.find(weld_key(0, m.position_[i]));
      const std::uint32_t head = first.value(slot);
      if (head == kNone) {
        first.set(slot, static_cast<std::uint32_t>(i));
        continue;
      }
      // Append i to the cycle that starts at head.
      m.partner_[last[head]] = static_cast<std::uint32_t>(i);
      m.partner_[i] = head;
      last[head] = static_cast<std::uint32_t>(i);
    }
  }
  m.sweep_kind_.assign(nd, kSweptNone);
  m.sweep_point_.assign(nd, Eigen::Vector3f::Zero());
  m.sweep_vector_.assign(nd, Eigen::Vector3f::Zero());
  m.sweep_radius_.assign(nd, 0.0f);
  m.line_.resize(nd);
  for (std::size_t i = 0; i < nd; ++i)
    m.line_[i] = {m.line_origin_[i], m.normal_[i], m.floor_[i], m.initial_height_[i]};
  m.stamp_.assign(nd, 0);
  m.old_height_.assign(nd, 0.0);
  m.threads_ = detail::CutThreads(options.threads > 0
                                      ? options.threads
                                      : std::max(1, int(std::thread::hardware_concurrency())));
  m.lowered_.assign(std::size_t(m.threads_.threads()), std::vector<std::uint32_t>(nd));
  m.chunks_.assign(kMaxChunks, {});
  m.cursor_.assign(std::size_t(m.threads_.threads()), {});
  if (nd == 0) return m;

  // Grid over the dexel lines [p + floor·n, p + h0·n].
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::max()), hi = -lo;
  auto line_box = [&](std::size_t i, Eigen::Vector3d& a, Eigen::Vector3d& b) {
    const Eigen::Vector3d p0 = m.line_origin_[i] + m.floor_[i] * m.normal_[i];
    const Eigen::Vector3d p1 = m.line_origin_[i] + m.initial_height_[i] * m.normal_[i];
    a = p0.cwiseMin(p1);
    b = p0.cwiseMax(p1);
  };
  for (std::size_t i = 0; i < nd; ++i) {
    Eigen::Vector3d a, b;
    line_box(i, a, b);
    lo = lo.cwiseMin(a);
    hi = hi.cwiseMax(b);
  }
  // Automatic cell: a dexel is listed in every cell its line crosses, so
  // cells well below the line length multiply the lists a tool scans; a
  // third of the mean length of the lines that hold stock measured best
  // (cutting_bench).
  double line_sum_mm = 0;
  std::size_t with_stock = 0;
  for (std::size_t i = 0; i < nd; ++i)
    if (m.initial_height_[i] > 0) {
      line_sum_mm += m.initial_height_[i] - m.floor_[i];
      ++with_stock;
    }
  const double mean_line_mm = with_stock > 0 ? line_sum_mm / double(with_stock) : 0;
  double cell = options.cell_mm > 0 ? options.cell_mm
                                    : std::max({4 * options.spacing_mm, 0.3 * mean_line_mm, 0.25});
  const Eigen::Vector3d extent = hi - lo;
  auto cells_for = [&](double c) {
    return (std::floor(extent.x() / c) + 1) * (std::floor(extent.y() / c) + 1) *
           (std::floor(extent.z() / c) + 1);
  };
  while (cells_for(cell) > 8e6)
    cell *= 1.25;
  m.cell_mm_ = cell;
  m.grid_origin_mm_ = lo;
  for (int i = 0; i < 3; ++i)
    m.grid_dims_[i] = static_cast<int>(std::floor(extent[i] / cell)) + 1;
  auto cell_range = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b, int* c0, int* c1) {
    for (int k = 0; k < 3; ++k) {
      c0[k] =
          std::clamp(static_cast<int>(std::floor((a[k] - lo[k]) / cell)), 0, m.grid_dims_[k] - 1);
      c1[k] =
          std::clamp(static_cast<int>(std::floor((b[k] - lo[k]) / cell)), 0, m.grid_dims_[k] - 1);
    }
  };
  const std::size_t ncells = std::size_t(m.grid_dims_[0]) * m.grid_dims_[1] * m.grid_dims_[2];
  m.cell_start_.assign(ncells + 1, 0);
  // fn(cell, flags): kFirstX/Y/Z where the cell is the first of the box.
  auto for_cells = [&](std::size_t i, auto&& fn) {
    Eigen::Vector3d a, b;
    line_box(i, a, b);
    int c0[3], c1[3];
    cell_range(a, b, c0, c1);
    for (int z = c0[2]; z <= c1[2]; ++z)
      for (int y = c0[1]; y <= c1[1]; ++y)
        for (int x = c0[0]; x <= c1[0]; ++x)
          fn((std::size_t(z) * m.grid_dims_[1] + y) * m.grid_dims_[0] + x,
             (x == c0[0] ? kFirstX : 0u) | (y == c0[1] ? kFirstY : 0u) |
                 (z == c0[2] ? kFirstZ : 0u),
             x, y, z);
  };
  static_assert(kMaxDexels <= kIndexMask + 1, "dexel index and first-cell flags share a word");
  std::size_t total = 0;
  for (std::size_t i = 0; i < nd; ++i)
    for_cells(i, [&](std::size_t c, std::uint32_t, int, int, int) {
      ++m.cell_start_[c + 1];
      ++total;
    });
  if (total >= 0xFFFFFFFFull)
    throw std::length_error("cutting: dexel grid too large; raise spacing_mm or cell size");
  for (std::size_t c = 0; c < ncells; ++c)
    m.cell_start_[c + 1] += m.cell_start_[c];
  m.cell_items_.resize(total);
  m.cell_reach_.assign(ncells, 0);
  std::vector<std::uint32_t> fill(m.cell_start_.begin(), m.cell_start_.end() - 1);
  for (std::size_t i = 0; i < nd; ++i) {
    Eigen::Vector3d a, b;
    line_box(i, a, b);
    // The line's top corner in eighths of a cell above the grid's origin.
    const Eigen::Vector3d top = (b - lo) * (8 / cell);
    for_cells(i, [&](std::size_t c, std::uint32_t flags, int x, int y, int z) {
      m.cell_items_[fill[c]++] = static_cast<std::uint32_t>(i) | flags;
      // The line's reach above the cell's low corner, in eighths of a cell:
      // truncated, plus one for rounding up and one for the rounding of the
      // corner itself.
      const int corner[3] = {x, y, z};
      std::uint32_t& reach = m.cell_reach_[c];
      for (int k = 0; k < 3; ++k) {
        const double eighths = top[k] - 8.0 * corner[k];
        const std::uint32_t r = eighths < double(kReachUnbounded - 3)
                                    ? std::uint32_t(std::max(eighths, 0.0)) + 2
                                    : kReachUnbounded;
        const std::uint32_t old = (reach >> (8 * k)) & 0xFFu;
        if (r > old) reach = (reach & ~(0xFFu << (8 * k))) | (r << (8 * k));
      }
    });
  }
  // In each cell the dexels whose box of cells starts there come first: inside
  // an instance's box only they are tested. The others follow grouped by
  // their flags (XY, XZ, X, YZ, Y, Z, none), each group in index order: a
  // cell on the edge of an instance's box scans them all and tests those with
  // the flags it needs, and the groups make that test predictable.
  m.cell_home_end_.resize(ncells);
  std::vector<std::uint32_t> sorted;
  for (std::size_t c = 0; c < ncells; ++c) {
    const std::uint32_t first = m.cell_start_[c], last = m.cell_start_[c + 1];
    m.cell_home_end_[c] = first;
    if (first == last) continue;
    std::uint32_t start[9] = {};
    for (std::uint32_t k = first; k < last; ++k)
      ++start[flag_group(m.cell_items_[k]) + 1];
    for (int g = 0; g < 8; ++g)
      start[g + 1] += start[g];
    m.cell_home_end_[c] = first + start[1];
    sorted.resize(last - first);
    for (std::uint32_t k = first; k < last; ++k)
      sorted[start[flag_group(m.cell_items_[k])]++] = m.cell_items_[k];
    std::copy(sorted.begin(), sorted.end(), m.cell_items_.begin() + first);
  }
  return m;
}

}  // namespace truecut::sim::cutting
