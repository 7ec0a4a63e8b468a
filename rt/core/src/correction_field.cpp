// Construction of a CorrectionField: validation and the B-spline prefilter.
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "truecut/rt/core/correction_field.hpp"

namespace truecut::rt {
namespace {

[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("correction field: " + what);
}

void validate_grid(const FieldGrid& grid) {
  static const char* const kAxis[] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(grid.origin_mm[a])) fail(std::string("origin ") + kAxis[a] + " not finite");
    if (!(std::isfinite(grid.spacing_mm[a]) && grid.spacing_mm[a] > 0.0))
      fail(std::string("spacing ") + kAxis[a] + " must be finite and > 0, is " +
           std::to_string(grid.spacing_mm[a]));
    if (grid.dims[a] < 2 || grid.dims[a] > CorrectionField::kMaxNodes)
      fail(std::string("dims ") + kAxis[a] + " must be >= 2, is " + std::to_string(grid.dims[a]));
  }
  if (grid.node_count() > CorrectionField::kMaxNodes)
    fail("too many nodes per layer: " + std::to_string(grid.node_count()) + " > " +
         std::to_string(CorrectionField::kMaxNodes));
}

void validate_layer(const FieldGrid& grid, const FieldLayer& layer) {
  const std::string name = "layer for tool " + std::to_string(layer.tool);
  if (layer.tool < 0) fail(name + ": tool number must be >= 0");
  if (static_cast<int64_t>(layer.nodes.size()) != grid.node_count())
    fail(name + ": " + std::to_string(layer.nodes.size()) + " nodes, grid has " +
         std::to_string(grid.node_count()));
  for (std::size_t n = 0; n < layer.nodes.size(); ++n) {
    const FieldNode& v = layer.nodes[n];
    if (!(std::isfinite(v.dx_mm) && std::isfinite(v.dy_mm) && std::isfinite(v.dz_mm)))
      fail(name + ": non-finite vector at node index " + std::to_string(n));
    if (!(v.weight >= 0.0 && v.weight <= 1.0))
      fail(name + ": weight " + std::to_string(v.weight) + " outside [0, 1] at node index " +
           std::to_string(n));
  }
  if (!layer.rotation_rad.empty() && layer.rotation_rad.size() != layer.nodes.size())
    fail(name + ": " + std::to_string(layer.rotation_rad.size()) + " rotations for " +
         std::to_string(layer.nodes.size()) + " nodes");
  for (std::size_t n = 0; n < layer.rotation_rad.size(); ++n)
    if (!layer.rotation_rad[n].allFinite())
      fail(name + ": non-finite rotation at node index " + std::to_string(n));
}

struct LineScratch {
  std::vector<Eigen::Vector3d> rhs;
  std::vector<double> super;  // super-diagonal after elimination
};

// Turns the node values of one line (entries 1..n of `line`, at stride
// `stride`) into cubic B-spline coefficients for entries 0..n+1, such that
// (c[i-1] + 4 c[i] + c[i+1]) / 6 reproduces node i, with natural end
// conditions (zero second derivative at both end nodes). The weight channel
// is only padded, by repeating the end nodes.
void prefilter_line(Eigen::Vector4d* line, int64_t stride, int32_t n, LineScratch& s) {
  auto at = [&](int32_t i) -> Eigen::Vector4d& { return line[(i + 1) * stride]; };
  // Natural conditions give c[0] = v[0] and c[n-1] = v[n-1]; the interior
  // c[1..n-2] solve a tridiagonal system with 1 4 1 rows (Thomas algorithm;
  // diagonally dominant, so stable without pivoting).
  const int32_t m = n - 2;
  if (m > 0) {
    s.rhs.resize(static_cast<std::size_t>(m));
    s.super.resize(static_cast<std::size_t>(m));
    for (int32_t r = 0; r < m; ++r)
      s.rhs[r] = 6.0 * at(r + 1).head<3>();
    s.rhs[0] -= at(0).head<3>();
    s.rhs[m - 1] -= at(n - 1).head<3>();
    double diag = 4.0;
    s.super[0] = 1.0 / diag;
    s.rhs[0] /= diag;
    for (int32_t r = 1; r < m; ++r) {
      diag = 4.0 - s.super[r - 1];
      s.super[r] = 1.0 / diag;
      s.rhs[r] = (s.rhs[r] - s.rhs[r - 1]) / diag;
    }
    for (int32_t r = m - 2; r >= 0; --r)
      s.rhs[r] -= s.super[r] * s.rhs[r + 1];
    for (int32_t r = 0; r < m; ++r)
      at(r + 1).head<3>() = s.rhs[r];
  }
  at(-1).head<3>() = 2.0 * at(0).head<3>() - at(1).head<3>();
  at(n).head<3>() = 2.0 * at(n - 1).head<3>() - at(n - 2).head<3>();
  at(-1)[3] = at(0)[3];
  at(n)[3] = at(n - 1)[3];
}

// The vectors the B-spline interpolates: a valid node's own; an invalid
// node's (weight 0: no data) is never used. It is replaced, in order of its
// distance (in face steps) from the valid nodes, by the mean of its
// neighbours one step nearer — so no invalid node's value enters the
// interpolation of its neighbours, and the spline does not ring at the
// edge of the data. A layer without valid nodes interpolates zeros.
// `value(n)` is node n's vector.
template <class Value>
std::vector<Eigen::Vector3d> usable_vectors(const FieldGrid& grid,
                                            const std::vector<FieldNode>& nodes, Value value) {
  std::vector<Eigen::Vector3d> v(nodes.size(), Eigen::Vector3d::Zero());
  std::vector<int32_t> step(nodes.size(), -1);  // face steps from the data; -1: not reached
  std::vector<int64_t> frontier, next;
  for (std::size_t n = 0; n < nodes.size(); ++n)
    if (nodes[n].weight > 0.0) {
      v[n] = value(n);
      step[n] = 0;
      frontier.push_back(static_cast<int64_t>(n));
    }
  const int64_t sx = 1, sy = grid.dims[0], sz = int64_t{grid.dims[0]} * grid.dims[1];
  auto for_neighbours = [&](int64_t n, auto&& fn) {
    const int64_t i = n % sy, j = (n / sy) % grid.dims[1], k = n / sz;
    const int64_t at[3] = {i, j, k}, stride[3] = {sx, sy, sz};
    for (int a = 0; a < 3; ++a) {
      if (at[a] > 0) fn(n - stride[a]);
      if (at[a] < grid.dims[a] - 1) fn(n + stride[a]);
    }
  };
  for (int32_t d = 1; !frontier.empty(); ++d) {
    next.clear();
    for (int64_t n : frontier)
      for_neighbours(n, [&](int64_t m) {
        if (step[m] == -1) {
          step[m] = d;
          next.push_back(m);
        }
      });
    for (int64_t m : next) {
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      int count = 0;
      for_neighbours(m, [&](int64_t q) {
        if (step[q] == d - 1) {
          sum += v[q];
          ++count;
        }
      });
      v[m] = sum / count;  // count >= 1: m was reached from one
    }
    std::swap(frontier, next);
  }
  return v;
}

template <class Value>
std::vector<Eigen::Vector4d> make_coefficients(const FieldGrid& grid,
                                               const std::vector<FieldNode>& nodes, Value value) {
  const std::vector<Eigen::Vector3d> vectors = usable_vectors(grid, nodes, value);
  const int32_t nx = grid.dims[0], ny = grid.dims[1], nz = grid.dims[2];
  const int64_t px = nx + 2, py = ny + 2, pz = nz + 2;
  std::vector<Eigen::Vector4d> c(static_cast<std::size_t>(px * py * pz), Eigen::Vector4d::Zero());
  auto padded = [&](int64_t i, int64_t j, int64_t k) { return &c[i + px * (j + py * k)]; };
  for (int32_t k = 0; k < nz; ++k)
    for (int32_t j = 0; j < ny; ++j)
      for (int32_t i = 0; i < nx; ++i) {
        const int64_t n = grid.index(i, j, k);
        const Eigen::Vector3d& v = vectors[static_cast<std::size_t>(n)];
        *padded(i + 1, j + 1, k + 1) = {v.x(), v.y(), v.z(), nodes[n].weight};
      }
  // Separable: along x on the node lines, then along y (including the x
  // padding), then along z (including both paddings).
  LineScratch scratch;
  for (int64_t k = 1; k <= nz; ++k)
    for (int64_t j = 1; j <= ny; ++j)
      prefilter_line(padded(0, j, k), 1, nx, scratch);
  for (int64_t k = 1; k <= nz; ++k)
    for (int64_t i = 0; i < px; ++i)
      prefilter_line(padded(i, 0, k), px, ny, scratch);
  for (int64_t j = 0; j < py; ++j)
    for (int64_t i = 0; i < px; ++i)
      prefilter_line(padded(i, j, 0), px * py, nz, scratch);
  return c;
}

}  // namespace

const char* to_string(FieldStatus status) noexcept {
  switch (status) {
    case FieldStatus::kOk:
      return "ok";
    case FieldStatus::kOutsideGrid:
      return "outside_grid";
    case FieldStatus::kNoLayerForTool:
      return "no_layer_for_tool";
    case FieldStatus::kNonFinite:
      return "non_finite";
  }
  return "unknown";
}

const char* to_string(FieldInterpolation interpolation) noexcept {
  switch (interpolation) {
    case FieldInterpolation::kTricubicBspline:
      return "tricubic-bspline";
    case FieldInterpolation::kTrilinear:
      return "trilinear";
  }
  return "unknown";
}

CorrectionField::CorrectionField(const FieldGrid& grid, std::vector<FieldLayer> layers,
                                 FieldInterpolation interpolation)
    : grid_(grid), interpolation_(interpolation) {
  validate_grid(grid_);
  if (layers.empty()) fail("no layers");
  if (layers.size() > kMaxLayers)
    fail(std::to_string(layers.size()) + " layers, at most " + std::to_string(kMaxLayers));
  for (const FieldLayer& layer : layers)
    validate_layer(grid_, layer);
  has_rotation_ = !layers.front().rotation_rad.empty();
  for (const FieldLayer& layer : layers)
    if (layer.rotation_rad.empty() == has_rotation_)
      fail("layer for tool " + std::to_string(layer.tool) +
           (has_rotation_ ? " has no rotation, another layer has"
                          : " has a rotation, another layer has none"));
  std::sort(layers.begin(), layers.end(),
            [](const FieldLayer& a, const FieldLayer& b) { return a.tool < b.tool; });
  for (std::size_t n = 1; n < layers.size(); ++n)
    if (layers[n].tool == layers[n - 1].tool)
      fail("two layers for tool " + std::to_string(layers[n].tool));

  tools_.reserve(layers.size());
  layers_.reserve(layers.size());
  for (FieldLayer& layer : layers) {
    tools_.push_back(layer.tool);
    Layer built;
    const std::vector<FieldNode>& nodes = layer.nodes;
    built.coefficients = make_coefficients(grid_, nodes, [&](std::size_t n) {
      return Eigen::Vector3d(nodes[n].dx_mm, nodes[n].dy_mm, nodes[n].dz_mm);
    });
    if (has_rotation_) {
      const std::vector<Eigen::Vector3d>& r = layer.rotation_rad;
      built.rotation_coefficients =
          make_coefficients(grid_, nodes, [&](std::size_t n) { return r[n]; });
      built.rotations = std::move(layer.rotation_rad);
    }
    built.nodes = std::move(layer.nodes);
    layers_.push_back(std::move(built));
  }
}

std::span<const FieldNode> CorrectionField::nodes(int32_t tool) const noexcept {
  const Layer* layer = find(tool);
  if (layer == nullptr) return {};
  return layer->nodes;
}

std::span<const Eigen::Vector3d> CorrectionField::rotations(int32_t tool) const noexcept {
  const Layer* layer = find(tool);
  if (layer == nullptr) return {};
  return layer->rotations;
}

}  // namespace truecut::rt
