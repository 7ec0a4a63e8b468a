#include "field_fit_grid.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <set>
#include <stdexcept>
#include <string>

namespace truecut::offline {
namespace fit_detail {

void check_options(const FieldFitOptions& o) {
  auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  auto non_negative = [](double v) { return std::isfinite(v) && v >= 0.0; };
  if (!positive(o.spacing_mm)) throw std::invalid_argument("field fit: spacing_mm must be > 0");
  if (!non_negative(o.smoothness))
    throw std::invalid_argument("field fit: smoothness must be >= 0");
  if (!positive(o.membrane_weight)) {
    throw std::invalid_argument("field fit: membrane_weight must be > 0");
  }
  if (!non_negative(o.support_radius_nodes) || !non_negative(o.fade_nodes)) {
    throw std::invalid_argument("field fit: support_radius_nodes and fade_nodes must be >= 0");
  }
  if (o.refinement_iterations < 0 || o.refinement_iterations > 20) {
    throw std::invalid_argument("field fit: refinement_iterations must be in [0, 20]");
  }
}

std::vector<float> node_distances(const rt::FieldGrid& grid, std::span<const FitSample> samples,
                                  double reach_nodes) {
  std::vector<float> d2(static_cast<std::size_t>(grid.node_count()),
                        std::numeric_limits<float>::infinity());
  const double h = grid.spacing_mm.x();
  // Samples in node units, bucketed by node layer (z) so that the layers can
  // be filled in parallel, each from the samples within reach of it.
  std::vector<Eigen::Vector3d> u;
  for (const FitSample& s : samples) {
    if (s.valid) u.push_back((s.position_mm - grid.origin_mm) / h);
  }
  const int32_t layers = grid.dims[2];
  std::vector<std::vector<std::uint32_t>> in_layer(static_cast<std::size_t>(layers));
  for (std::size_t p = 0; p < u.size(); ++p) {
    const auto k = std::clamp(static_cast<int32_t>(std::floor(u[p].z())), 0, layers - 1);
    in_layer[static_cast<std::size_t>(k)].push_back(static_cast<std::uint32_t>(p));
  }
  // Samples at the same position stamp the same values: one of them is
  // enough (a path sample cuts several points: on a wall cut by a long flank
  // most samples have a few twins).
  tbb::parallel_for(std::size_t{0}, in_layer.size(), [&](std::size_t k) {
    std::vector<std::uint32_t>& list = in_layer[k];
    auto less = [&](std::uint32_t a, std::uint32_t b) {
      const Eigen::Vector3d &p = u[a], &q = u[b];
      return p.x() != q.x() ? p.x() < q.x() : p.y() != q.y() ? p.y() < q.y() : p.z() < q.z();
    };
    std::sort(list.begin(), list.end(), less);
    list.erase(std::unique(list.begin(), list.end(),
                           [&](std::uint32_t a, std::uint32_t b) { return u[a] == u[b]; }),
               list.end());
  });
  const double reach2 = reach_nodes * reach_nodes;
  const auto reach_layers = static_cast<int32_t>(std::ceil(reach_nodes)) + 1;
  // Every node gets min(its value, its exact squared distance to the
  // sample), so updating a node outside a sample's ball is harmless: its
  // value there is beyond the reach, as good as infinity to every user. That
  // lets each row of a sample's ball run over the ball's full width in x
  // with no square root per row.
  tbb::parallel_for(int32_t{0}, layers, [&](int32_t k) {
    const int32_t b0 = std::max(0, k - reach_layers), b1 = std::min(layers - 1, k + reach_layers);
    for (int32_t b = b0; b <= b1; ++b) {
      for (std::uint32_t p : in_layer[static_cast<std::size_t>(b)]) {
        const Eigen::Vector3d& q = u[p];
        const double dz2 = (k - q.z()) * (k - q.z());
        if (dz2 > reach2) continue;
        const double ry = std::sqrt(reach2 - dz2);
        const int32_t j0 = std::max(0, static_cast<int32_t>(std::ceil(q.y() - ry)));
        const int32_t j1 = std::min(grid.dims[1] - 1, static_cast<int32_t>(std::floor(q.y() + ry)));
        const int32_t i0 = std::max(0, static_cast<int32_t>(std::ceil(q.x() - reach_nodes)));
        const int32_t i1 =
            std::min(grid.dims[0] - 1, static_cast<int32_t>(std::floor(q.x() + reach_nodes)));
        for (int32_t j = j0; j <= j1; ++j) {
          const double dyz2 = dz2 + (j - q.y()) * (j - q.y());
          float* row = d2.data() + grid.index(0, j, k);
          for (int32_t i = i0; i <= i1; ++i) {
            const double dx = i - q.x();
            row[i] = std::min(row[i], static_cast<float>(dyz2 + dx * dx));
          }
        }
      }
    }
  });
  tbb::parallel_for(std::size_t{0}, d2.size(), [&](std::size_t n) { d2[n] = std::sqrt(d2[n]); });
  return d2;
}

std::vector<double> node_weights(const rt::FieldGrid& grid, std::span<const float> distance_nodes,
                                 const FieldFitOptions& o) {
  std::vector<double> w(distance_nodes.size(), 0.0);
  tbb::parallel_for(int32_t{0}, grid.dims[2], [&](int32_t k) {
    for (int32_t j = 0; j < grid.dims[1]; ++j) {
      for (int32_t i = 0; i < grid.dims[0]; ++i) {
        const std::array<int32_t, 3> ijk{i, j, k};
        bool outer = false;
        for (int a = 0; a < 3; ++a)
          outer |= ijk[a] < 2 || ijk[a] > grid.dims[a] - 3;
        if (outer) continue;
        const auto n = static_cast<std::size_t>(grid.index(i, j, k));
        const double d = distance_nodes[n];
        if (d <= o.support_radius_nodes) {
          w[n] = 1.0;
        } else if (d < o.support_radius_nodes + o.fade_nodes) {
          const double t = (d - o.support_radius_nodes) / o.fade_nodes;
          w[n] = 1.0 - t * t * (3.0 - 2.0 * t);
        }
      }
    }
  });
  return w;
}

CellPosition cell_of(const rt::FieldGrid& grid, const Eigen::Vector3d& position_mm) {
  const Eigen::Vector3d u = (position_mm - grid.origin_mm).cwiseQuotient(grid.spacing_mm);
  CellPosition c;
  std::array<int32_t*, 3> idx{&c.i, &c.j, &c.k};
  for (int a = 0; a < 3; ++a) {
    const int32_t cell = std::clamp(static_cast<int32_t>(std::floor(u[a])), 0, grid.dims[a] - 2);
    *idx[a] = cell;
    c.t[a] = std::clamp(u[a] - cell, 0.0, 1.0);
  }
  return c;
}

}  // namespace fit_detail

rt::FieldGrid field_fit_grid(std::span<const ToolSamples> tools, const FieldFitOptions& options) {
  fit_detail::check_options(options);
  if (tools.empty()) throw std::invalid_argument("field fit: no tools");
  std::set<int32_t> seen;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  int64_t valid = 0;
  for (const ToolSamples& t : tools) {
    if (t.tool < 0 || !seen.insert(t.tool).second) {
      throw std::invalid_argument("field fit: tool " + std::to_string(t.tool) +
                                  " is negative or given twice");
    }
    for (std::size_t s = 0; s < t.samples.size(); ++s) {
      const FitSample& p = t.samples[s];
      if (!p.valid) continue;
      if (!p.position_mm.allFinite() || !p.vector_mm.allFinite()) {
        throw std::invalid_argument("field fit: tool " + std::to_string(t.tool) + " sample " +
                                    std::to_string(s) + " is valid but not finite");
      }
      lo = lo.cwiseMin(p.position_mm);
      hi = hi.cwiseMax(p.position_mm);
      ++valid;
    }
  }
  if (valid == 0) throw std::invalid_argument("field fit: no valid sample");

  const double h = options.spacing_mm;
  const double margin_mm = (options.support_radius_nodes + options.fade_nodes + 2.0) * h;
  rt::FieldGrid grid;
  grid.spacing_mm = Eigen::Vector3d::Constant(h);
  int64_t nodes = 1;
  for (int a = 0; a < 3; ++a) {
    const double extent_nodes = (hi[a] - lo[a] + 2.0 * margin_mm) / h;
    if (extent_nodes > 1e6) throw std::invalid_argument("field fit: grid too large");
    const auto cells = static_cast<int32_t>(std::ceil(extent_nodes));
    grid.dims[a] = std::max(cells + 1, 2);
    // Centre the grid on the data.
    grid.origin_mm[a] = 0.5 * (lo[a] + hi[a]) - 0.5 * cells * h;
    nodes *= grid.dims[a];
  }
  if (nodes > rt::CorrectionField::kMaxNodes) {
    throw std::invalid_argument("field fit: " + std::to_string(nodes) +
                                " nodes per layer exceed the field's limit; raise spacing_mm");
  }
  return grid;
}

}  // namespace truecut::offline
