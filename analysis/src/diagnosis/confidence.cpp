// Confidence intervals of the fitted parameters, and the parameters the
// data cannot separate.
#include <algorithm>
#include <cmath>

#include "effect_params.hpp"
#include "fit_steps.hpp"

namespace truecut::analysis::diagnosis {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// Covariance of the parameters from the Jacobian J of the weighted
// residual r: each axis with its own residual variance and its own
// correlation inflation (1 + ρ₁)/(1 − ρ₁), cov = (Σ_a J_aᵀJ_a / (s²_a f_a))⁻¹.
// Pooling the axes would let an axis the effect does not touch (e.g. one
// that matches its model to the count) shrink the interval of one it does.
MatrixXd parameter_covariance(const Layout& layout, const MatrixXd& J, const VectorXd& r) {
  const Eigen::Index p = J.cols();
  const double n = double(r.size());
  MatrixXd info = MatrixXd::Zero(p, p);
  Eigen::Index row = 0;
  for (const auto& ix : layout.index) {
    const Eigen::Index m = Eigen::Index(ix.size());
    if (m == 0) continue;
    const auto seg = r.segment(row, m);
    double num = 0, den = seg.squaredNorm();
    for (Eigen::Index i = 1; i < m; ++i)
      if (ix[std::size_t(i)] == ix[std::size_t(i - 1)] + 1) num += seg[i] * seg[i - 1];
    const double rho = std::clamp(den > 0 ? num / den : 0.0, 0.0, 0.99);
    const double s2 = den / double(m) * n / std::max(1.0, n - double(p));
    const double var = std::max(s2 * (1 + rho) / (1 - rho), 1e-4);
    const auto Ja = J.middleRows(row, m);
    info += Ja.transpose() * Ja / var;
    row += m;
  }
  return Eigen::CompleteOrthogonalDecomposition<MatrixXd>(info).pseudoInverse();
}

namespace {

// Each parameter's value and 95 % interval, in fit.parameters and per effect.
void set_parameters(const VectorXd& th, const MatrixXd& cov, ModelFit& fit) {
  Eigen::Index i = 0;
  for (const auto& s : fit.selected) {
    std::vector<Parameter> ps;
    for (const auto& k : s.keys) {
      Parameter p;
      p.name = k;
      p.value = th[i];
      const double se = std::sqrt(std::max(0.0, cov(i, i)));
      p.ci95_lo = th[i] - 1.96 * se;
      p.ci95_hi = th[i] + 1.96 * se;
      ps.push_back(p);
      fit.parameters.push_back(p);
      ++i;
    }
    fit.per_effect.push_back(ps);
  }
}

// Parameters of different effects the data cannot separate (|correlation| ≥ 0.99).
void add_correlated(const std::vector<Key>& keys, const MatrixXd& cov, ModelFit& fit) {
  const Eigen::Index m = Eigen::Index(keys.size());
  for (Eigen::Index a = 0; a < m; ++a)
    for (Eigen::Index b = a + 1; b < m; ++b) {
      const double d = std::sqrt(cov(a, a) * cov(b, b));
      const double corr = d > 0 ? cov(a, b) / d : 0;
      if (std::abs(corr) < 0.99) continue;
      NotIdentifiable ni;
      ni.first = keys[std::size_t(a)].effect + ":" + keys[std::size_t(a)].key;
      ni.second = keys[std::size_t(b)].effect + ":" + keys[std::size_t(b)].key;
      ni.correlation = corr;
      ni.separate_by =
          keys[std::size_t(a)].effect == keys[std::size_t(b)].effect
              ? "moves at several speeds and accelerations"
              : separation_hint(keys[std::size_t(a)].effect, keys[std::size_t(b)].effect);
      fit.not_identifiable.push_back(ni);
    }
}

// The Jacobian for the covariance. A servo loop's Kv and ff1 move the
// re-simulated position by about one encoder count per fitting step
// (0.1 % of Kv: 2.5 µs of lag, 0.1 µm at 40 mm/s), and the encoder's
// quantisation inside the loop makes that difference jitter: the jitter
// adds to the column's norm, not to its fit, and the interval came out
// narrower than the estimate's scatter. Their columns are taken as central
// differences over ten fitting steps instead.
MatrixXd covariance_jacobian(const FitContext& ctx, const sim::MachineParams& params,
                             const std::vector<Key>& keys, const VectorXd& th, const VectorXd& r0) {
  MatrixXd J = jacobian(ctx, params, keys, th, r0);
  for (std::size_t i = 0; i < keys.size(); ++i) {
    if (keys[i].effect != "servo_lag") continue;
    const Eigen::Index c = Eigen::Index(i);
    const double h = 10 * param_step(keys[i].key, th[c]);
    // Within the parameter's range (ff1 ≥ 0): the step shortened at an end.
    const double hi = clamp_param(keys[i].key, th[c] + h), lo = clamp_param(keys[i].key, th[c] - h);
    if (!(hi > lo)) continue;
    auto at = [&](double v) {
      sim::MachineParams p = params;
      VectorXd t = th;
      t[c] = v;
      set_theta(p, keys, t);
      return weighted_residual(ctx, p);
    };
    J.col(c) = (at(hi) - at(lo)) / (hi - lo);
  }
  return J;
}

}  // namespace

// Confidence intervals from the Jacobian at the solution, inflated for
// correlated residuals (effective sample count).
void report_intervals(const FitContext& ctx, ModelFit& fit) {
  const auto keys = keys_of(fit.selected);
  const Eigen::Index m = Eigen::Index(keys.size());
  const VectorXd r0 = weighted_residual(ctx, fit.params);
  fit.rss = r0.squaredNorm();
  const double rho = ctx.layout.lag1(r0);
  fit.n_eff = n_eff_of(double(fit.n), rho);
  fit.k = int(m);
  VectorXd th = get_theta(fit.params, keys);
  MatrixXd cov = MatrixXd::Zero(m, m);
  if (m > 0) {
    const MatrixXd J = covariance_jacobian(ctx, fit.params, keys, th, r0);
    cov = parameter_covariance(ctx.layout, J, r0);
  }
  set_parameters(th, cov, fit);
  add_correlated(keys, cov, fit);
}

}  // namespace truecut::analysis::diagnosis
