// The weighted residual the fit minimises, its layout, and the parameter
// vector the nonlinear fit moves.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "effect_params.hpp"
#include "fit_steps.hpp"
#include "truecut/rt/number_format.hpp"

namespace truecut::analysis::diagnosis {

using Eigen::MatrixXd;
using Eigen::VectorXd;

std::string fmt4g(double v) {
  return rt::format_printf("%.4g", v);
}

// The residual sum of squares of `r` after least squares on the columns of X.
double rss_after(const MatrixXd& X, const VectorXd& r, VectorXd* coef) {
  if (X.cols() == 0) {
    if (coef) coef->resize(0);
    return r.squaredNorm();
  }
  Eigen::ColPivHouseholderQR<MatrixXd> qr(X);
  qr.setThreshold(1e-10);
  const VectorXd c = qr.solve(r);
  if (coef) *coef = c;
  return (r - X * c).squaredNorm();
}

MatrixXd hcat(const std::vector<const MatrixXd*>& parts, Eigen::Index rows) {
  Eigen::Index cols = 0;
  for (const auto* p : parts)
    cols += p->cols();
  MatrixXd X(rows, cols);
  Eigen::Index c = 0;
  for (const auto* p : parts) {
    X.middleCols(c, p->cols()) = *p;
    c += p->cols();
  }
  return X;
}

double n_eff_of(double n, double rho) {
  rho = std::clamp(rho, 0.0, 0.99);
  return std::max(2.0, n * (1.0 - rho) / (1.0 + rho));
}

std::vector<Key> keys_of(const std::vector<SelectedEffect>& sel) {
  std::vector<Key> keys;
  for (const auto& s : sel)
    for (const auto& k : s.keys)
      keys.push_back({s.effect, s.joint, k});
  return keys;
}

void set_theta(sim::MachineParams& p, const std::vector<Key>& keys, const VectorXd& th) {
  for (std::size_t i = 0; i < keys.size(); ++i)
    if (double* v = param_ptr(p, keys[i].effect, keys[i].joint, keys[i].key))
      *v = clamp_param(keys[i].key, th[Eigen::Index(i)]);
}

VectorXd get_theta(sim::MachineParams& p, const std::vector<Key>& keys) {
  VectorXd th(Eigen::Index(keys.size()));
  for (std::size_t i = 0; i < keys.size(); ++i) {
    const double* v = param_ptr(p, keys[i].effect, keys[i].joint, keys[i].key);
    th[Eigen::Index(i)] = v ? *v : 0.0;
  }
  return th;
}

// Amplitude kept positive, phase in (−180, 180].
void normalise_periodic(sim::MachineParams& p) {
  for (auto& a : p.effects.pitch_error.axes) {
    if (!a) continue;
    if (a->periodic_amplitude_um < 0) {
      a->periodic_amplitude_um = -a->periodic_amplitude_um;
      a->periodic_phase_deg += 180.0;
    }
    a->periodic_phase_deg = std::remainder(a->periodic_phase_deg, 360.0);
  }
}

// Forward-difference Jacobian of the weighted residual in `keys` at theta
// (r0: the residual there), one re-simulation per parameter.
MatrixXd jacobian(const FitContext& ctx, const sim::MachineParams& params,
                  const std::vector<Key>& keys, const VectorXd& theta, const VectorXd& r0) {
  MatrixXd j(r0.size(), theta.size());
  for (Eigen::Index i = 0; i < theta.size(); ++i) {
    sim::MachineParams p = params;
    VectorXd t2 = theta;
    const double h = param_step(keys[std::size_t(i)].key, theta[i]);
    t2[i] += h;
    set_theta(p, keys, t2);
    j.col(i) = (weighted_residual(ctx, p) - r0) / h;
  }
  return j;
}

std::size_t Layout::size() const {
  std::size_t n = 0;
  for (const auto& ix : index)
    n += ix.size();
  return n;
}

VectorXd Layout::stack(const std::array<std::vector<double>, sim::kJointCount>& v) const {
  VectorXd out(static_cast<Eigen::Index>(size()));
  Eigen::Index r = 0;
  for (std::size_t a = 0; a < axes.size(); ++a) {
    const auto& src = v[axes[a]];
    for (std::size_t i = 0; i < index[a].size(); ++i)
      out[r++] = src.empty() ? 0.0 : src[index[a][i]] * w(a, i);
  }
  return out;
}

void Layout::center(Eigen::Ref<VectorXd> v) const {
  Eigen::Index r = 0;
  for (std::size_t a = 0; a < index.size(); ++a) {
    const Eigen::Index m = Eigen::Index(index[a].size());
    if (m > 0 && sample_weight.empty()) {
      v.segment(r, m).array() -= v.segment(r, m).mean();
    } else if (m > 0) {
      const Eigen::Map<const VectorXd> u(sample_weight[a].data(), m);
      const double uu = u.squaredNorm();
      if (uu > 0) v.segment(r, m) -= u * (u.dot(v.segment(r, m)) / uu);
    }
    r += m;
  }
}

double Layout::lag1(const VectorXd& v) const {
  double num = 0, den = 0;
  Eigen::Index r = 0;
  for (const auto& ix : index) {
    const Eigen::Index m = Eigen::Index(ix.size());
    for (Eigen::Index i = 0; i < m; ++i) {
      den += v[r + i] * v[r + i];
      if (i > 0 && ix[std::size_t(i)] == ix[std::size_t(i - 1)] + 1) num += v[r + i] * v[r + i - 1];
    }
    r += m;
  }
  return den > 0 ? num / den : 0.0;
}

double ModelFit::bic() const {
  if (n == 0) return 0.0;
  return n_eff * std::log(std::max(rss, 1e-300) / double(n)) + k * std::log(n_eff);
}

Simulated simulate_aligned(const FitContext& ctx, const sim::MachineParams& params) {
  Simulated sim = resimulate(params, *ctx.trace, ctx.max_period_s, ctx.cache);
  delay_simulated(ctx.trace->t_s, sim, ctx.delay_s);
  return sim;
}

std::array<std::vector<double>, sim::kJointCount> simulate_aligned_targets(
    const FitContext& ctx, const sim::MachineParams& params) {
  Simulated sim = resimulate(params, *ctx.trace, ctx.max_period_s, ctx.cache);
  if (ctx.delay_s != 0.0)
    for (auto& v : sim.target)
      v = delayed(ctx.trace->t_s, v, ctx.delay_s);
  return std::move(sim.target);
}

VectorXd weighted_residual(const FitContext& ctx, const sim::MachineParams& params) {
  VectorXd r =
      ctx.layout.stack(ctx.aligned) - ctx.layout.stack(simulate_aligned_targets(ctx, params));
  ctx.layout.center(r);
  return r;
}

}  // namespace truecut::analysis::diagnosis
