#include "truecut/offline/field_fit.hpp"

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/Sparse>

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

#include "field_fit_grid.hpp"
#include "multilevel_bspline.hpp"

namespace truecut::offline {
namespace {

using SpMat = Eigen::SparseMatrix<double>;
using Triplets = std::vector<Eigen::Triplet<double>>;

// Active nodes are the unknowns; everything else is fixed at 0.
struct Unknowns {
  std::vector<int64_t> of_node;  // -1 when the node is not an unknown
  int64_t count = 0;
};

Unknowns active_nodes(std::span<const float> distance_nodes, double reach_nodes) {
  Unknowns u;
  u.of_node.assign(distance_nodes.size(), -1);
  for (std::size_t n = 0; n < distance_nodes.size(); ++n) {
    if (distance_nodes[n] <= reach_nodes) u.of_node[n] = u.count++;
  }
  return u;
}

// Rows of first (order 1) or second (order 2) differences along every axis,
// kept only where every node of the stencil is an unknown and farther than
// min_distance_nodes from the data.
SpMat difference_rows(const rt::FieldGrid& g, const Unknowns& u, int order,
                      std::span<const float> distance_nodes, double min_distance_nodes) {
  Triplets t;
  Eigen::Index row = 0;
  const std::array<double, 3> second{1.0, -2.0, 1.0};
  const std::array<double, 2> first{-1.0, 1.0};
  for (int a = 0; a < 3; ++a) {
    for (int32_t k = 0; k < g.dims[2]; ++k) {
      for (int32_t j = 0; j < g.dims[1]; ++j) {
        for (int32_t i = 0; i < g.dims[0]; ++i) {
          std::array<int32_t, 3> ijk{i, j, k};
          if (ijk[a] + order >= g.dims[a]) continue;
          std::array<int64_t, 3> col{};
          bool all = true;
          for (int s = 0; s <= order && all; ++s) {
            std::array<int32_t, 3> q = ijk;
            q[a] += s;
            const auto n = static_cast<std::size_t>(g.index(q[0], q[1], q[2]));
            col[s] = u.of_node[n];
            all = col[s] >= 0 && distance_nodes[n] > min_distance_nodes;
          }
          if (!all) continue;
          for (int s = 0; s <= order; ++s) {
            t.emplace_back(row, col[s], order == 2 ? second[s] : first[s]);
          }
          ++row;
        }
      }
    }
  }
  SpMat d(row, u.count);
  d.setFromTriplets(t.begin(), t.end());
  return d;
}

// Trilinear weights of the valid samples (rows) on the unknowns (columns).
SpMat trilinear_rows(const rt::FieldGrid& g, const Unknowns& u, std::span<const FitSample> samples,
                     int64_t valid) {
  Triplets t;
  t.reserve(static_cast<std::size_t>(valid) * 8);
  Eigen::Index row = 0;
  for (const FitSample& s : samples) {
    if (!s.valid) continue;
    const fit_detail::CellPosition c = fit_detail::cell_of(g, s.position_mm);
    for (int corner = 0; corner < 8; ++corner) {
      const int di = corner & 1, dj = (corner >> 1) & 1, dk = (corner >> 2) & 1;
      const double w = (di ? c.t.x() : 1.0 - c.t.x()) * (dj ? c.t.y() : 1.0 - c.t.y()) *
                       (dk ? c.t.z() : 1.0 - c.t.z());
      const int64_t col =
          u.of_node[static_cast<std::size_t>(g.index(c.i + di, c.j + dj, c.k + dk))];
      if (w != 0.0 && col >= 0) t.emplace_back(row, col, w);
    }
    ++row;
  }
  SpMat a(row, u.count);
  a.setFromTriplets(t.begin(), t.end());
  return a;
}

rt::FieldLayer make_layer(int32_t tool, const Unknowns& u, const Eigen::MatrixX3d& x,
                          std::span<const double> weights) {
  rt::FieldLayer layer;
  layer.tool = tool;
  layer.nodes.resize(weights.size());
  for (std::size_t n = 0; n < weights.size(); ++n) {
    rt::FieldNode& node = layer.nodes[n];
    node.weight = weights[n];
    if (const int64_t c = u.of_node[n]; c >= 0) {
      node.dx_mm = x(c, 0);
      node.dy_mm = x(c, 1);
      node.dz_mm = x(c, 2);
    }
  }
  return layer;
}

// Residual v − vector(p) of the tricubic evaluator at the valid samples.
Eigen::MatrixX3d evaluator_residual(const rt::FieldGrid& g, const rt::FieldLayer& layer,
                                    std::span<const FitSample> samples, int64_t valid) {
  const rt::CorrectionField field(g, {layer});
  Eigen::MatrixX3d r(valid, 3);
  Eigen::Index row = 0;
  for (const FitSample& s : samples) {
    if (!s.valid) continue;
    const rt::FieldSample e = field.evaluate_tricubic(layer.tool, s.position_mm);
    r.row(row++) = (s.vector_mm - e.vector_mm).transpose();
  }
  return r;
}

double rms(const Eigen::MatrixX3d& r) {
  return r.rows() == 0 ? 0.0 : std::sqrt(r.rowwise().squaredNorm().mean());
}

struct FittedLayer {
  rt::FieldLayer layer;
  FieldFitLayerStats stats;
};

// Below this many unknowns CG converges fast enough from zero.
constexpr int64_t kCoarseStartUnknowns = 4000;

FittedLayer fit_layer(const rt::FieldGrid& g, const ToolSamples& tool, const FieldFitOptions& o);

// Initial guess from the same fit on a grid of twice the spacing (itself
// started the same way): CG then only has to resolve the fine detail, not
// the smooth extension into the fade region, which takes it most iterations.
Eigen::MatrixX3d coarse_guess(const rt::FieldGrid& g, const Unknowns& u, const ToolSamples& tool,
                              const FieldFitOptions& o) {
  FieldFitOptions oc = o;
  oc.spacing_mm = 2.0 * o.spacing_mm;
  oc.refinement_iterations = 0;
  const ToolSamples one[] = {tool};
  const rt::FieldGrid gc = field_fit_grid(one, oc);
  FittedLayer coarse = fit_layer(gc, tool, oc);
  const rt::CorrectionField field(gc, {std::move(coarse.layer)});
  Eigen::MatrixX3d x0 = Eigen::MatrixX3d::Zero(u.count, 3);
  for (int32_t k = 0; k < g.dims[2]; ++k)
    for (int32_t j = 0; j < g.dims[1]; ++j)
      for (int32_t i = 0; i < g.dims[0]; ++i) {
        const int64_t c = u.of_node[static_cast<std::size_t>(g.index(i, j, k))];
        if (c < 0) continue;
        const rt::FieldSample e = field.evaluate_tricubic(tool.tool, g.node_position_mm(i, j, k));
        if (e.status == rt::FieldStatus::kOk) x0.row(c) = e.vector_mm.transpose();
      }
  return x0;
}

FittedLayer fit_layer(const rt::FieldGrid& g, const ToolSamples& tool, const FieldFitOptions& o) {
  // The multilevel fit needs distances only for the weights.
  const double reach_nodes = o.method == FieldFitMethod::kMultilevelBspline
                                 ? o.support_radius_nodes + o.fade_nodes
                                 : o.support_radius_nodes + o.fade_nodes + 2.0;
  const std::vector<float> dist = fit_detail::node_distances(g, tool.samples, reach_nodes);
  const std::vector<double> weights = fit_detail::node_weights(g, dist, o);
  const Unknowns u = active_nodes(dist, reach_nodes);

  FittedLayer out;
  out.stats.tool = tool.tool;
  out.stats.unknown_nodes = u.count;
  int64_t valid = 0;
  for (const FitSample& s : tool.samples)
    valid += s.valid ? 1 : 0;
  out.stats.valid_samples = valid;
  if (valid == 0) {
    out.layer.tool = tool.tool;
    out.layer.nodes.assign(weights.size(), rt::FieldNode{});
    return out;
  }

  if (o.method == FieldFitMethod::kMultilevelBspline) {
    const std::vector<Eigen::Vector3d> values =
        fit_detail::multilevel_bspline_nodes(g, tool.samples, o);
    out.layer.tool = tool.tool;
    out.layer.nodes.resize(weights.size());
    for (std::size_t n = 0; n < weights.size(); ++n)
      out.layer.nodes[n] = {values[n].x(), values[n].y(), values[n].z(), weights[n]};
    return out;  // residual statistics: from the finished field, see below
  }

  int64_t support_nodes = 0;
  for (float d : dist)
    support_nodes += d <= o.support_radius_nodes ? 1 : 0;
  const double rho =
      static_cast<double>(valid) / static_cast<double>(std::max<int64_t>(support_nodes, 1));

  const SpMat a = trilinear_rows(g, u, tool.samples, valid);
  const SpMat d2 = difference_rows(g, u, 2, dist, -1.0);
  const SpMat d1 = difference_rows(g, u, 1, dist, o.support_radius_nodes);
  const SpMat reg = SpMat(o.smoothness * rho * SpMat(d2.transpose() * d2) +
                          o.membrane_weight * rho * SpMat(d1.transpose() * d1));
  const SpMat m = SpMat(SpMat(a.transpose() * a) + reg);

  // A direct factorisation fills in badly on a 3-D grid (seconds for 20k
  // unknowns); preconditioned CG converges in a few hundred iterations.
  Eigen::ConjugateGradient<SpMat, Eigen::Lower | Eigen::Upper, Eigen::IncompleteCholesky<double>>
      solver;
  solver.setTolerance(1e-10);
  solver.setMaxIterations(20000);
  solver.compute(m);
  if (solver.info() != Eigen::Success) throw std::runtime_error("field fit: preconditioner failed");

  Eigen::MatrixX3d v(valid, 3);
  Eigen::Index row = 0;
  for (const FitSample& s : tool.samples) {
    if (s.valid) v.row(row++) = s.vector_mm.transpose();
  }
  const Eigen::MatrixX3d rhs = a.transpose() * v;
  Eigen::MatrixX3d x =
      u.count > kCoarseStartUnknowns
          ? Eigen::MatrixX3d(solver.solveWithGuess(rhs, coarse_guess(g, u, tool, o)))
          : Eigen::MatrixX3d(solver.solve(rhs));
  out.layer = make_layer(tool.tool, u, x, weights);
  Eigen::MatrixX3d r = evaluator_residual(g, out.layer, tool.samples, valid);
  double best = rms(r);

  // Fixed point: Aᵀ(v − T x) = R x, T the tricubic evaluator.
  for (int it = 0; it < o.refinement_iterations; ++it) {
    const Eigen::MatrixX3d b = a.transpose() * r - reg * x;
    // The step is small: solve it to the accuracy of the first solve, not
    // relative to its own (small) right-hand side.
    solver.setTolerance(std::min(1e-2, 1e-10 * rhs.norm() / std::max(b.norm(), 1e-300)));
    const Eigen::MatrixX3d step = solver.solve(b);
    const Eigen::MatrixX3d candidate = x + step;
    rt::FieldLayer layer = make_layer(tool.tool, u, candidate, weights);
    Eigen::MatrixX3d rc = evaluator_residual(g, layer, tool.samples, valid);
    if (rms(rc) >= best) break;
    best = rms(rc);
    x = candidate;
    r = std::move(rc);
    out.layer = std::move(layer);
  }
  out.stats.residual_rms_mm = best;
  out.stats.residual_max_mm = r.rowwise().norm().maxCoeff();
  return out;
}

}  // namespace

FieldFitResult fit_correction_field(std::span<const ToolSamples> tools,
                                    const FieldFitOptions& options) {
  const rt::FieldGrid grid = field_fit_grid(tools, options);
  std::vector<rt::FieldLayer> layers;
  std::vector<FieldFitLayerStats> stats;
  for (const ToolSamples& t : tools) {
    FittedLayer f = fit_layer(grid, t, options);
    layers.push_back(std::move(f.layer));
    stats.push_back(f.stats);
  }
  rt::CorrectionField field(grid, std::move(layers));
  if (options.method == FieldFitMethod::kMultilevelBspline) {
    for (std::size_t t = 0; t < tools.size(); ++t) {
      // Per sample in parallel, summed in order: the same on any thread
      // count. The field is evaluated once per distinct position (a path
      // sample cuts several points).
      const std::vector<FitSample>& samples = tools[t].samples;
      std::vector<std::uint32_t> order;
      for (std::size_t i = 0; i < samples.size(); ++i)
        if (samples[i].valid) order.push_back(static_cast<std::uint32_t>(i));
      tbb::parallel_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
        const Eigen::Vector3d &p = samples[a].position_mm, &q = samples[b].position_mm;
        return p.x() != q.x() ? p.x() < q.x() : p.y() != q.y() ? p.y() < q.y() : p.z() < q.z();
      });
      std::vector<std::uint32_t> distinct, distinct_of(samples.size(), 0);
      for (const std::uint32_t i : order) {
        if (distinct.empty() || samples[i].position_mm != samples[distinct.back()].position_mm)
          distinct.push_back(i);
        distinct_of[i] = static_cast<std::uint32_t>(distinct.size() - 1);
      }
      std::vector<Eigen::Vector3d> value(distinct.size());
      tbb::parallel_for(std::size_t{0}, distinct.size(), [&](std::size_t k) {
        value[k] =
            field.evaluate_tricubic(tools[t].tool, samples[distinct[k]].position_mm).vector_mm;
      });
      std::vector<double> e2(samples.size(), 0.0);
      tbb::parallel_for(std::size_t{0}, samples.size(), [&](std::size_t i) {
        const FitSample& s = samples[i];
        if (!s.valid) return;
        const Eigen::Vector3d d = s.vector_mm - value[distinct_of[i]];
        e2[i] = s.along_normal_only ? std::pow(s.normal.normalized().dot(d), 2) : d.squaredNorm();
      });
      double sum2 = 0.0, max2 = 0.0;
      for (double v : e2) {
        sum2 += v;
        max2 = std::max(max2, v);
      }
      if (stats[t].valid_samples > 0) {
        stats[t].residual_rms_mm = std::sqrt(sum2 / static_cast<double>(stats[t].valid_samples));
        stats[t].residual_max_mm = std::sqrt(max2);
      }
    }
  }
  return {std::move(field), std::move(stats)};
}

}  // namespace truecut::offline
