#include "multilevel_bspline.hpp"

#include <Eigen/Eigenvalues>

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <optional>

namespace truecut::offline::fit_detail {
namespace {

// Uniform cubic B-spline basis at t in [0, 1]: weights of control points
// cell − 1 … cell + 2.
std::array<double, 4> cubic_basis(double t) {
  const double s = 1.0 - t;
  return {s * s * s / 6.0, (3.0 * t * t * t - 6.0 * t * t + 4.0) / 6.0,
          (-3.0 * t * t * t + 3.0 * t * t + 3.0 * t + 1.0) / 6.0, t * t * t / 6.0};
}

// One control lattice: spacing ratio × grid spacing, aligned with grid node
// 0. Control point I (I = −1 … last_cell + 2) is stored at I + 1.
struct Lattice {
  int32_t ratio = 1;
  std::array<int32_t, 3> last_cell{};  // last cell index holding grid nodes
  std::array<int32_t, 3> n{};          // control points per axis
  std::vector<Eigen::Vector3d> phi;

  Lattice(const rt::FieldGrid& g, int32_t r) : ratio(r) {
    for (int a = 0; a < 3; ++a) {
      last_cell[a] = (g.dims[a] - 1) / r;
      n[a] = last_cell[a] + 4;
    }
    phi.assign(static_cast<std::size_t>(n[0]) * n[1] * n[2], Eigen::Vector3d::Zero());
  }
  std::size_t at(int32_t i, int32_t j, int32_t k) const {  // i, j, k already offset
    return static_cast<std::size_t>(i + int64_t{n[0]} * (j + int64_t{n[1]} * k));
  }
};

struct Stencil {
  std::array<int32_t, 3> first{};  // stored index of the first control point per axis
  std::array<std::array<double, 4>, 3> b{};
};

Stencil stencil_of(const rt::FieldGrid& g, const Lattice& l, const Eigen::Vector3d& p_mm) {
  Stencil s;
  for (int a = 0; a < 3; ++a) {
    const double u = (p_mm[a] - g.origin_mm[a]) / (g.spacing_mm[a] * l.ratio);
    const int32_t cell = std::clamp(static_cast<int32_t>(std::floor(u)), 0, l.last_cell[a]);
    s.first[a] = cell;  // control point cell − 1 is stored at cell
    s.b[a] = cubic_basis(std::clamp(u - cell, 0.0, 1.0));
  }
  return s;
}

Eigen::Vector3d evaluate(const Lattice& l, const Stencil& s) {
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  for (int c = 0; c < 4; ++c)
    for (int b = 0; b < 4; ++b) {
      const double wbc = s.b[1][b] * s.b[2][c];
      const std::size_t row = l.at(s.first[0], s.first[1] + b, s.first[2] + c);
      for (int a = 0; a < 4; ++a)
        v += (s.b[0][a] * wbc) * l.phi[row + a];
    }
  return v;
}

// Lee, Wolberg & Shin's closed form: each sample alone would be reproduced by
// the control values w_c r / Σ w²; every control point takes the w²-weighted
// mean of what its samples ask for.
// damping ≥ 0 shrinks control values with little data behind them: the
// denominator gets damping × its mean over the control points with data.
//
// In parallel and deterministic, the sums over the samples taken in an order
// fixed by the data alone, whatever the number of threads:
// - a lattice with at least 8 slabs of 4 control planes along its longest
//   axis: a sample, filed under the slab of its first control plane, writes
//   into that slab and the next; even slabs run in parallel, then odd ones,
//   each over its samples in input order;
// - a coarser (small) lattice: 8 fixed runs of consecutive samples sum into
//   their own copies, which are then added in run order.
//
// A sample known only along its normal n (a ray-method error vector: the
// scan says nothing about the tangential components) weighs its residual r
// with P = β I + (1 − β) n nᵀ, β = kTangentialWeight: the normal component
// fully, the tangential ones (taken as zero: a face pass should not be moved
// sideways) at β. Each control point then solves M φ = Σ w² (w / Σw²) P r,
// M = Σ w² P. Where only one normal is seen this is exactly the classic
// closed form. Where a wall's samples (normal x) and a face's (normal z)
// share a control point, the wall sets x and the face z, each hardly pulled
// by the other's assumed zero (the classic form averages them: a wall's
// correction lost a quarter at its foot). A face alone still keeps its
// tangential components at zero (a face pass at a convex edge shifted
// sideways by a wall's correction left a strip of stock on benchmark004),
// and M's smallest eigenvalue is at least β·Σw², so nearly parallel noisy
// normals (a curved surface) cannot blow a tangential component up.
using Sym = std::array<double, 6>;  // xx, yy, zz, xy, xz, yz

// See fit_level: the weight of a normal-only sample's tangential components
// (taken as zero) against its normal component.
constexpr double kTangentialWeight = 0.02;

// Sums per control point, kept from level to level so the finest lattice's
// memory is allocated once, not once per pass.
struct LevelSums {
  std::vector<Eigen::Vector3d> num;
  std::vector<double> den;  // Σ w² of every sample
  std::vector<Sym> sym;     // Σ w² n nᵀ of the normal-only samples
};

// The samples at one position (a path sample cuts several points): they
// share a stencil, so the closed form's sums over them are taken first and
// scattered to the 64 control points once. What they ask for enters the
// sums linearly: Σ r (each normal-only residual weighed by P first), the
// count, Σ n nᵀ of the normal-only ones.
struct SampleGroup {
  Eigen::Vector3d r = Eigen::Vector3d::Zero();
  double count = 0.0;
  Sym nn{};
  bool any_normal_only = false;
};

void fit_level(Lattice& l, std::span<const Stencil> stencils, std::span<const SampleGroup> groups,
               bool any_normal_only, double damping, LevelSums& sums) {
  sums.num.assign(l.phi.size(), Eigen::Vector3d::Zero());
  sums.den.assign(l.phi.size(), 0.0);
  sums.sym.assign(any_normal_only ? l.phi.size() : 0, Sym{});
  std::vector<Eigen::Vector3d>& num = sums.num;
  std::vector<double>& den = sums.den;
  std::vector<Sym>& sym = sums.sym;
  auto accumulate = [&](std::uint32_t p, Eigen::Vector3d* to_num, double* to_den, Sym* to_sym) {
    const Stencil& s = stencils[p];
    const SampleGroup& g = groups[p];
    double sum2 = 1.0;
    for (int a = 0; a < 3; ++a) {
      double q = 0.0;
      for (double w : s.b[a])
        q += w * w;
      sum2 *= q;
    }
    const bool along_normal = to_sym && g.any_normal_only;
    for (int c = 0; c < 4; ++c)
      for (int b = 0; b < 4; ++b) {
        const double wbc = s.b[1][b] * s.b[2][c];
        const std::size_t row = l.at(s.first[0], s.first[1] + b, s.first[2] + c);
        for (int a = 0; a < 4; ++a) {
          const double w = s.b[0][a] * wbc;
          const double w2 = w * w;
          to_num[row + a] += (w2 * w / sum2) * g.r;
          to_den[row + a] += w2 * g.count;
          if (along_normal)
            for (int k = 0; k < 6; ++k)
              to_sym[row + a][k] += w2 * g.nn[k];
        }
      }
  };
  int axis = 0;
  for (int a = 1; a < 3; ++a)
    if (l.n[a] > l.n[axis]) axis = a;
  constexpr int32_t kSlab = 4, kMinSlabs = 8, kRuns = 8;
  const int32_t slabs = (l.n[axis] + kSlab - 1) / kSlab;
  Sym* const sym_data = any_normal_only ? sym.data() : nullptr;
  if (slabs >= kMinSlabs) {
    std::vector<std::vector<std::uint32_t>> in_slab(static_cast<std::size_t>(slabs));
    for (std::size_t p = 0; p < stencils.size(); ++p)
      in_slab[static_cast<std::size_t>(stencils[p].first[axis] / kSlab)].push_back(
          static_cast<std::uint32_t>(p));
    for (int32_t parity = 0; parity < 2; ++parity) {
      tbb::parallel_for(int32_t{0}, (slabs - parity + 1) / 2, [&](int32_t h) {
        for (std::uint32_t p : in_slab[static_cast<std::size_t>(2 * h + parity)])
          accumulate(p, num.data(), den.data(), sym_data);
      });
    }
  } else {
    std::vector<std::vector<Eigen::Vector3d>> run_num(kRuns);
    std::vector<std::vector<double>> run_den(kRuns);
    std::vector<std::vector<Sym>> run_sym(kRuns);
    tbb::parallel_for(0, kRuns, [&](int run) {
      run_num[run].assign(l.phi.size(), Eigen::Vector3d::Zero());
      run_den[run].assign(l.phi.size(), 0.0);
      run_sym[run].assign(any_normal_only ? l.phi.size() : 0, Sym{});
      const std::size_t n = stencils.size();
      for (std::size_t p = n * run / kRuns; p < n * (run + 1) / kRuns; ++p)
        accumulate(static_cast<std::uint32_t>(p), run_num[run].data(), run_den[run].data(),
                   any_normal_only ? run_sym[run].data() : nullptr);
    });
    tbb::parallel_for(std::size_t{0}, l.phi.size(), [&](std::size_t c) {
      for (int run = 0; run < kRuns; ++run) {
        num[c] += run_num[run][c];
        den[c] += run_den[run][c];
        if (any_normal_only)
          for (int k = 0; k < 6; ++k)
            sym[c][k] += run_sym[run][c][k];
      }
    });
  }
  double mean = 0.0;
  std::size_t with_data = 0;
  for (double d : den) {
    mean += d;
    with_data += d > 0.0 ? 1 : 0;
  }
  const double extra = with_data > 0 ? damping * mean / static_cast<double>(with_data) : 0.0;
  tbb::parallel_for(std::size_t{0}, l.phi.size(), [&](std::size_t c) {
    if (!(den[c] > 0.0)) {
      l.phi[c].setZero();
      return;
    }
    const bool has_normal_only =
        any_normal_only && (sym[c][0] != 0.0 || sym[c][1] != 0.0 || sym[c][2] != 0.0);
    if (!has_normal_only) {
      l.phi[c] = num[c] / (den[c] + extra);
      return;
    }
    // M = (Σ w² of full samples + β Σ w² of normal-only ones)·I
    //     + (1 − β) Σ w² n nᵀ, plus the ridge; symmetric positive definite.
    const Sym& m = sym[c];
    const double normal_only = m[0] + m[1] + m[2];
    const double iso =
        std::max(den[c] - normal_only, 0.0) + kTangentialWeight * normal_only + extra;
    const double k = 1.0 - kTangentialWeight;
    Eigen::Matrix3d a;
    a << k * m[0] + iso, k * m[3], k * m[4], k * m[3], k * m[1] + iso, k * m[5], k * m[4], k * m[5],
        k * m[2] + iso;
    l.phi[c] = a.ldlt().solve(num[c]);
  });
}

// Adds the lattice's values at every grid node, one axis at a time (each
// node coordinate is a fixed fraction of a lattice cell).
void add_at_nodes(const rt::FieldGrid& g, const Lattice& l, std::vector<Eigen::Vector3d>& nodes) {
  std::array<std::vector<Stencil>, 3> axis;  // per axis and node: first control point, basis
  for (int a = 0; a < 3; ++a) {
    axis[a].resize(static_cast<std::size_t>(g.dims[a]));
    for (int32_t i = 0; i < g.dims[a]; ++i) {
      const int32_t cell = std::min(i / l.ratio, l.last_cell[a]);
      Stencil& s = axis[a][static_cast<std::size_t>(i)];
      s.first[0] = cell;
      s.b[0] = cubic_basis(static_cast<double>(i - cell * l.ratio) / l.ratio);
    }
  }
  // x: (n0, n1, n2) → (d0, n1, n2); y: → (d0, d1, n2); z: → (d0, d1, d2).
  const int64_t d0 = g.dims[0], d1 = g.dims[1], d2 = g.dims[2];
  const int64_t n0 = l.n[0], n1 = l.n[1], n2 = l.n[2];
  std::vector<Eigen::Vector3d> tx(static_cast<std::size_t>(d0 * n1 * n2));
  tbb::parallel_for(int64_t{0}, n2, [&](int64_t k) {
    for (int64_t j = 0; j < n1; ++j)
      for (int64_t i = 0; i < d0; ++i) {
        const Stencil& s = axis[0][static_cast<std::size_t>(i)];
        Eigen::Vector3d v = Eigen::Vector3d::Zero();
        for (int a = 0; a < 4; ++a)
          v += s.b[0][a] * l.phi[static_cast<std::size_t>(s.first[0] + a + n0 * (j + n1 * k))];
        tx[static_cast<std::size_t>(i + d0 * (j + n1 * k))] = v;
      }
  });
  std::vector<Eigen::Vector3d> ty(static_cast<std::size_t>(d0 * d1 * n2));
  tbb::parallel_for(int64_t{0}, n2, [&](int64_t k) {
    for (int64_t j = 0; j < d1; ++j) {
      const Stencil& s = axis[1][static_cast<std::size_t>(j)];
      for (int64_t i = 0; i < d0; ++i) {
        Eigen::Vector3d v = Eigen::Vector3d::Zero();
        for (int a = 0; a < 4; ++a)
          v += s.b[0][a] * tx[static_cast<std::size_t>(i + d0 * (s.first[0] + a + n1 * k))];
        ty[static_cast<std::size_t>(i + d0 * (j + d1 * k))] = v;
      }
    }
  });
  tbb::parallel_for(int64_t{0}, d2, [&](int64_t k) {
    const Stencil& s = axis[2][static_cast<std::size_t>(k)];
    for (int64_t j = 0; j < d1; ++j)
      for (int64_t i = 0; i < d0; ++i) {
        Eigen::Vector3d v = Eigen::Vector3d::Zero();
        for (int a = 0; a < 4; ++a)
          v += s.b[0][a] * ty[static_cast<std::size_t>(i + d0 * (j + d1 * (s.first[0] + a)))];
        nodes[static_cast<std::size_t>(i + d0 * (j + d1 * k))] += v;
      }
  });
}

// v ≈ value + gradient (p − centre), least squares. Only along directions in
// which the samples spread by at least min_spread_mm (standard deviation);
// along the others (e.g. the normal of a plane of samples) the part is
// constant. A B-spline reproduces an affine function exactly, so the levels
// only have to fit what is left: this gives the fit linear precision up to
// the rim of the data, where the local averages of the levels are one-sided.
struct Affine {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Vector3d value = Eigen::Vector3d::Zero();
  Eigen::Matrix3d gradient = Eigen::Matrix3d::Zero();  // (component, axis)
  Eigen::Vector3d operator()(const Eigen::Vector3d& p) const {
    return value + gradient * (p - centre);
  }
};

Affine fit_affine(std::span<const Eigen::Vector3d> positions,
                  std::span<const Eigen::Vector3d> values, double min_spread_mm) {
  Affine f;
  if (positions.empty()) return f;
  const double n = static_cast<double>(positions.size());
  for (std::size_t p = 0; p < positions.size(); ++p) {
    f.centre += positions[p];
    f.value += values[p];
  }
  f.centre /= n;
  f.value /= n;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero(), cross = Eigen::Matrix3d::Zero();
  for (std::size_t p = 0; p < positions.size(); ++p) {
    const Eigen::Vector3d d = positions[p] - f.centre;
    cov += d * d.transpose();
    cross += (values[p] - f.value) * d.transpose();
  }
  cov /= n;
  cross /= n;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  Eigen::Matrix3d pinv = Eigen::Matrix3d::Zero();
  for (int a = 0; a < 3; ++a) {
    const double lambda = eig.eigenvalues()[a];
    if (lambda < min_spread_mm * min_spread_mm) continue;
    pinv += eig.eigenvectors().col(a) * eig.eigenvectors().col(a).transpose() / lambda;
  }
  f.gradient = cross * pinv;
  return f;
}

}  // namespace

std::vector<Eigen::Vector3d> multilevel_bspline_nodes(const rt::FieldGrid& grid,
                                                      std::span<const FitSample> samples,
                                                      const FieldFitOptions& o) {
  std::vector<Eigen::Vector3d> positions, residuals, normal;
  bool any_normal_only = false;
  for (const FitSample& s : samples) {
    if (!s.valid) continue;
    positions.push_back(s.position_mm);
    residuals.push_back(s.vector_mm);
    // Zero: the whole vector is known; else only its component along this.
    normal.push_back(s.along_normal_only ? s.normal.normalized() : Eigen::Vector3d::Zero());
    any_normal_only = any_normal_only || s.along_normal_only;
  }
  // The affine part is fitted to the whole vectors, also where only their
  // normal component is measured (taken as zero across the normal): a global
  // 12-unknown fit to the normal components alone is as ill-conditioned as
  // a single control point with nearly parallel normals, and the levels
  // below correct the measured components locally anyway.
  const Affine affine = fit_affine(positions, residuals, grid.spacing_mm.x());
  for (std::size_t p = 0; p < positions.size(); ++p)
    residuals[p] -= affine(positions[p]);
  std::vector<Eigen::Vector3d> nodes(static_cast<std::size_t>(grid.node_count()));
  tbb::parallel_for(int32_t{0}, grid.dims[2], [&](int32_t k) {
    for (int32_t j = 0; j < grid.dims[1]; ++j)
      for (int32_t i = 0; i < grid.dims[0]; ++i)
        nodes[static_cast<std::size_t>(grid.index(i, j, k))] =
            affine(grid.node_position_mm(i, j, k));
  });
  // Coarsest lattice: at most ~4 cells along the grid's longest axis.
  const int32_t longest = std::max({grid.dims[0], grid.dims[1], grid.dims[2]}) - 1;
  int32_t ratio = 1;
  while (longest / ratio > 4)
    ratio *= 2;
  // Levels coarse to fine, then `refinement_iterations` more passes on the
  // finest lattice (spacing_mm) to take up what is left.
  std::vector<int32_t> ratios;
  for (int32_t r = ratio; r >= 1; r /= 2)
    ratios.push_back(r);
  for (int it = 0; it < o.refinement_iterations; ++it)
    ratios.push_back(1);
  // The passes on the finest lattice are summed before they are evaluated
  // at the nodes (the evaluation is linear), the coarser levels one by one.
  // Samples at the same position (a path sample cuts several points) get
  // the same value of a lattice: it is evaluated once per distinct position.
  std::vector<std::uint32_t> order(positions.size()), distinct_of_sample(positions.size());
  std::iota(order.begin(), order.end(), std::uint32_t{0});
  tbb::parallel_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    const Eigen::Vector3d &p = positions[a], &q = positions[b];
    return p.x() != q.x() ? p.x() < q.x() : p.y() != q.y() ? p.y() < q.y() : p.z() < q.z();
  });
  std::vector<std::uint32_t> distinct;  // a sample at each distinct position
  for (const std::uint32_t p : order) {
    if (distinct.empty() || positions[p] != positions[distinct.back()]) distinct.push_back(p);
    distinct_of_sample[p] = static_cast<std::uint32_t>(distinct.size() - 1);
  }
  // Each position's samples in sample order (a counting sort): the order of
  // every sum below is fixed by the data alone, whatever the thread count.
  std::vector<std::uint32_t> member_begin(distinct.size() + 1, 0), members(positions.size());
  for (const std::uint32_t d : distinct_of_sample)
    ++member_begin[d + 1];
  std::partial_sum(member_begin.begin(), member_begin.end(), member_begin.begin());
  {
    std::vector<std::uint32_t> next(member_begin.begin(), member_begin.end() - 1);
    for (std::size_t p = 0; p < positions.size(); ++p)
      members[next[distinct_of_sample[p]]++] = static_cast<std::uint32_t>(p);
  }
  std::vector<Eigen::Vector3d> at_distinct(distinct.size());
  std::vector<SampleGroup> groups(distinct.size());
  std::optional<Lattice> finest, pass;
  std::vector<Stencil> stencils(distinct.size());
  int32_t stencil_ratio = 0;
  LevelSums sums;
  for (int32_t r : ratios) {
    if (!pass || pass->ratio != r) pass.emplace(grid, r);
    Lattice& l = *pass;
    if (r != stencil_ratio) {
      tbb::parallel_for(std::size_t{0}, distinct.size(), [&](std::size_t d) {
        stencils[d] = stencil_of(grid, l, positions[distinct[d]]);
      });
      stencil_ratio = r;
    }
    tbb::parallel_for(std::size_t{0}, distinct.size(), [&](std::size_t d) {
      SampleGroup g;
      for (std::uint32_t m = member_begin[d]; m < member_begin[d + 1]; ++m) {
        const std::uint32_t p = members[m];
        const Eigen::Vector3d& n = normal[p];
        g.count += 1.0;
        if (!any_normal_only || n.isZero()) {
          g.r += residuals[p];
          continue;
        }
        g.r +=
            kTangentialWeight * residuals[p] + (1.0 - kTangentialWeight) * n * n.dot(residuals[p]);
        const Sym nn{n.x() * n.x(), n.y() * n.y(), n.z() * n.z(),
                     n.x() * n.y(), n.x() * n.z(), n.y() * n.z()};
        for (int k = 0; k < 6; ++k)
          g.nn[k] += nn[k];
        g.any_normal_only = true;
      }
      groups[d] = g;
    });
    fit_level(l, stencils, groups, any_normal_only, r == 1 ? o.smoothness : 0.0, sums);
    tbb::parallel_for(std::size_t{0}, distinct.size(),
                      [&](std::size_t d) { at_distinct[d] = evaluate(l, stencils[d]); });
    tbb::parallel_for(std::size_t{0}, positions.size(),
                      [&](std::size_t p) { residuals[p] -= at_distinct[distinct_of_sample[p]]; });
    if (r != 1) {
      add_at_nodes(grid, l, nodes);
    } else if (!finest) {
      finest = l;
    } else {
      tbb::parallel_for(std::size_t{0}, l.phi.size(),
                        [&](std::size_t c) { finest->phi[c] += l.phi[c]; });
    }
  }
  if (finest) add_at_nodes(grid, *finest, nodes);
  return nodes;
}

}  // namespace truecut::offline::fit_detail
