#include "truecut/offline/truss_smoothing.hpp"

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

namespace truecut::offline {
namespace {

using Edge = std::array<std::uint32_t, 2>;

// Relative residual |b − A d| / |b| at which conjugate gradients stop: far
// below a micrometre on any compensation vector.
constexpr double kTolerance = 1e-12;
constexpr Eigen::Index kMaxCgIterations = 300;

std::uint32_t find_root(std::vector<std::uint32_t>& parent, std::uint32_t i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

// Per vertex: does its connected component contain a valid vertex?
std::vector<std::uint8_t> supported_vertices(std::size_t n, std::span<const Edge> edges,
                                             std::span<const std::uint8_t> valid) {
  std::vector<std::uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0u);
  for (const Edge& e : edges) {
    const std::uint32_t a = find_root(parent, e[0]);
    const std::uint32_t b = find_root(parent, e[1]);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
  std::vector<std::uint8_t> root_has_valid(n, 0);
  for (std::uint32_t i = 0; i < n; ++i) {
    if (valid[i]) root_has_valid[find_root(parent, i)] = 1;
  }
  std::vector<std::uint8_t> supported(n);
  for (std::uint32_t i = 0; i < n; ++i)
    supported[i] = root_has_valid[find_root(parent, i)];
  return supported;
}

std::vector<double> bar_stiffness(std::span<const Eigen::Vector3d> vertices_mm,
                                  std::span<const Edge> edges, const TrussOptions& options) {
  std::vector<double> k(edges.size(), options.kb_over_kc);
  if (options.edge_weight == TrussEdgeWeight::kUniform || edges.empty()) return k;
  std::vector<double> length_mm(edges.size());
  double sum_mm = 0.0;
  for (std::size_t e = 0; e < edges.size(); ++e) {
    length_mm[e] = (vertices_mm[edges[e][0]] - vertices_mm[edges[e][1]]).norm();
    sum_mm += length_mm[e];
  }
  const double mean_mm = sum_mm / static_cast<double>(edges.size());
  for (std::size_t e = 0; e < edges.size(); ++e) {
    // A zero-length bar would be infinitely stiff; cap it at 1000× the mean.
    k[e] *= mean_mm / std::max(length_mm[e], 1e-3 * mean_mm);
  }
  return k;
}

void check_inputs(std::span<const Eigen::Vector3d> vertices_mm, std::span<const Triangle> triangles,
                  std::span<const Eigen::Vector3d> vectors_mm, std::span<const std::uint8_t> valid,
                  const TrussOptions& options) {
  const std::size_t n = vectors_mm.size();
  if (valid.size() != n) {
    throw std::invalid_argument("smooth_truss: " + std::to_string(n) + " vectors but " +
                                std::to_string(valid.size()) + " valid flags");
  }
  if (options.edge_weight == TrussEdgeWeight::kInverseLength && vertices_mm.size() != n) {
    throw std::invalid_argument("smooth_truss: inverse_length needs one vertex per vector");
  }
  if (options.stiffness == TrussStiffness::kAxialBars && vertices_mm.size() != n) {
    throw std::invalid_argument("smooth_truss: axial bars need one vertex per vector");
  }
  if (!std::isfinite(options.kb_over_kc) || options.kb_over_kc < 0.0) {
    throw std::invalid_argument("smooth_truss: kb_over_kc must be finite and >= 0");
  }
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    for (std::uint32_t v : triangles[t]) {
      if (v >= n) {
        throw std::invalid_argument("smooth_truss: triangle " + std::to_string(t) +
                                    " refers to vertex " + std::to_string(v) + " of " +
                                    std::to_string(n));
      }
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (valid[i] && !vectors_mm[i].allFinite()) {
      throw std::invalid_argument("smooth_truss: valid vector " + std::to_string(i) +
                                  " is not finite");
    }
  }
}

}  // namespace

std::vector<Edge> truss_bars(std::span<const Triangle> triangles) {
  std::vector<Edge> edges;
  edges.reserve(triangles.size() * 3);
  for (const Triangle& t : triangles) {
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t a = t[c];
      const std::uint32_t b = t[(c + 1) % 3];
      if (a != b) edges.push_back({std::min(a, b), std::max(a, b)});
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  return edges;
}

namespace {

// Axial bars (the source's truss): a 3n × 3n system, x, y, z coupled
// through each bar's direction. Solved by a sparse LDLᵀ factorisation: the
// spring that removes mechanisms makes it far too ill-conditioned for
// conjugate gradients.
Eigen::MatrixX3d solve_axial_bars(std::span<const Eigen::Vector3d> vertices_mm,
                                  std::span<const Edge> edges, std::span<const double> k,
                                  std::span<const Eigen::Vector3d> vectors_mm,
                                  std::span<const std::uint8_t> valid, TrussResult& result) {
  const std::size_t n = vectors_mm.size();
  const auto dim = static_cast<Eigen::Index>(3 * n);
  const double k_max = k.empty() ? 0.0 : *std::max_element(k.begin(), k.end());
  const double mechanism_spring = 1e-9 * std::max(k_max, 1.0);
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(3 * n + 36 * edges.size());
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(dim);
  for (std::size_t i = 0; i < n; ++i) {
    const double c = valid[i] || !result.supported[i] ? 1.0 : mechanism_spring;
    if (!valid[i] && !result.supported[i]) ++result.unsupported_count;
    for (int r = 0; r < 3; ++r) {
      const auto row = static_cast<Eigen::Index>(3 * i + r);
      triplets.emplace_back(row, row, c);
      if (valid[i]) rhs(row) = vectors_mm[i](r);
    }
  }
  for (std::size_t e = 0; e < edges.size(); ++e) {
    const Eigen::Vector3d along = vertices_mm[edges[e][1]] - vertices_mm[edges[e][0]];
    const double length_mm = along.norm();
    if (!(length_mm > 0.0)) continue;  // coincident vertices: no direction, no bar
    const Eigen::Matrix3d block = k[e] * (along / length_mm) * (along / length_mm).transpose();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) {
        const auto ar = static_cast<Eigen::Index>(3 * edges[e][0] + r);
        const auto ac = static_cast<Eigen::Index>(3 * edges[e][0] + c);
        const auto br = static_cast<Eigen::Index>(3 * edges[e][1] + r);
        const auto bc = static_cast<Eigen::Index>(3 * edges[e][1] + c);
        triplets.emplace_back(ar, ac, block(r, c));
        triplets.emplace_back(br, bc, block(r, c));
        triplets.emplace_back(ar, bc, -block(r, c));
        triplets.emplace_back(br, ac, -block(r, c));
      }
    }
  }
  Eigen::SparseMatrix<double> a(dim, dim);
  a.setFromTriplets(triplets.begin(), triplets.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(a);
  if (solver.info() != Eigen::Success) {
    throw std::runtime_error("smooth_truss: factorisation of the axial-bar truss failed");
  }
  const Eigen::VectorXd d = solver.solve(rhs);
  Eigen::MatrixX3d out(static_cast<Eigen::Index>(n), 3);
  for (std::size_t i = 0; i < n; ++i)
    out.row(static_cast<Eigen::Index>(i)) = d.segment<3>(static_cast<Eigen::Index>(3 * i));
  return out;
}

}  // namespace

TrussResult smooth_truss(std::span<const Eigen::Vector3d> vertices_mm,
                         std::span<const Triangle> triangles,
                         std::span<const Eigen::Vector3d> vectors_mm,
                         std::span<const std::uint8_t> valid, const TrussOptions& options) {
  check_inputs(vertices_mm, triangles, vectors_mm, valid, options);
  const std::size_t n = vectors_mm.size();
  const std::vector<Edge> edges = truss_bars(triangles);
  const std::vector<double> k = bar_stiffness(vertices_mm, edges, options);

  TrussResult result;
  result.edge_count = static_cast<std::int64_t>(edges.size());
  result.supported = supported_vertices(n, edges, valid);
  result.displacement_mm.assign(n, Eigen::Vector3d::Zero());
  if (n == 0) return result;
  if (options.stiffness == TrussStiffness::kAxialBars) {
    const Eigen::MatrixX3d d = solve_axial_bars(vertices_mm, edges, k, vectors_mm, valid, result);
    for (std::size_t i = 0; i < n; ++i)
      result.displacement_mm[i] = d.row(static_cast<Eigen::Index>(i)).transpose();
    return result;
  }

  // Unsupported vertices keep c_i = 1 and v_i = 0: their block solves to
  // d = 0 exactly and the whole matrix stays positive definite.
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(n + 4 * edges.size());
  Eigen::MatrixX3d rhs = Eigen::MatrixX3d::Zero(static_cast<Eigen::Index>(n), 3);
  for (std::size_t i = 0; i < n; ++i) {
    const auto ii = static_cast<Eigen::Index>(i);
    if (valid[i]) {
      triplets.emplace_back(ii, ii, 1.0);
      rhs.row(ii) = vectors_mm[i].transpose();
    } else if (!result.supported[i]) {
      triplets.emplace_back(ii, ii, 1.0);
      ++result.unsupported_count;
    }
  }
  for (std::size_t e = 0; e < edges.size(); ++e) {
    const auto a = static_cast<Eigen::Index>(edges[e][0]);
    const auto b = static_cast<Eigen::Index>(edges[e][1]);
    triplets.emplace_back(a, a, k[e]);
    triplets.emplace_back(b, b, k[e]);
    triplets.emplace_back(a, b, -k[e]);
    triplets.emplace_back(b, a, -k[e]);
  }
  Eigen::SparseMatrix<double> a(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  a.setFromTriplets(triplets.begin(), triplets.end());

  // kb_over_kc = 0 leaves invalid-but-supported vertices with an empty row;
  // they are then exactly what the (absent) truss says: nothing. Give them
  // d = 0 rather than a singular solve.
  for (std::size_t i = 0; i < n; ++i) {
    const auto ii = static_cast<Eigen::Index>(i);
    if (a.coeff(ii, ii) == 0.0) a.coeffRef(ii, ii) = 1.0;
  }

  // Conjugate gradients with a Jacobi preconditioner, from the measured
  // vectors: the matrix is symmetric positive definite and, where most
  // vertices are valid, well conditioned (c_i = 1 dominates kb/kc·K), so it
  // converges in a few tens of iterations (28 at the source's scale, against
  // 3× the time for a sparse factorisation). Large invalid regions (pure
  // Laplace interpolation) or a very stiff truss converge slowly: then the
  // sparse LDLᵀ factorisation solves it directly.
  Eigen::MatrixX3d d(static_cast<Eigen::Index>(n), 3);
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper,
                           Eigen::DiagonalPreconditioner<double>>
      cg;
  cg.setTolerance(kTolerance);
  cg.setMaxIterations(kMaxCgIterations);
  cg.compute(a);
  bool solved = cg.info() == Eigen::Success;
  for (int c = 0; c < 3 && solved; ++c) {
    d.col(c) = cg.solveWithGuess(rhs.col(c), rhs.col(c));
    solved = cg.info() == Eigen::Success;
  }
  if (!solved) {
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(a);
    if (solver.info() != Eigen::Success) {
      throw std::runtime_error("smooth_truss: factorisation failed");
    }
    d = solver.solve(rhs);
  }
  for (std::size_t i = 0; i < n; ++i) {
    result.displacement_mm[i] = d.row(static_cast<Eigen::Index>(i)).transpose();
  }
  return result;
}

}  // namespace truecut::offline
