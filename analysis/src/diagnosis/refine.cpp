// The nonlinear fit: the selected effects' parameters by re-simulation.
#include <algorithm>
#include <cmath>

#include "effect_params.hpp"
#include "fit_steps.hpp"
#include "trace.hpp"

namespace truecut::analysis::diagnosis {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// Levenberg–Marquardt on every parameter of fit.selected by re-simulation
// (numeric Jacobian, at most 12 iterations); updates fit.params and fit.rss.
void refine(const FitContext& ctx, ModelFit& fit) {
  const auto keys = keys_of(fit.selected);
  VectorXd th = get_theta(fit.params, keys);
  VectorXd r0 = weighted_residual(ctx, fit.params);
  double rss0 = r0.squaredNorm(), lambda = 1e-3;
  for (int it = 0; it < 12 && th.size() > 0; ++it) {
    const MatrixXd J = jacobian(ctx, fit.params, keys, th, r0);
    const MatrixXd A = J.transpose() * J;
    const VectorXd g = J.transpose() * r0;
    bool improved = false;
    for (int tries = 0; tries < 6 && !improved; ++tries) {
      MatrixXd Ad = A;
      Ad.diagonal().array() *= (1.0 + lambda);
      Ad.diagonal().array() += 1e-12;
      const VectorXd step = Ad.ldlt().solve(-g);
      sim::MachineParams p = fit.params;
      VectorXd t2 = th + step;
      set_theta(p, keys, t2);
      t2 = get_theta(p, keys);
      const VectorXd r1 = weighted_residual(ctx, p);
      const double rss1 = r1.squaredNorm();
      if (rss1 < rss0) {
        const double gain = (rss0 - rss1) / rss0;
        th = t2, r0 = r1, rss0 = rss1, fit.params = p;
        lambda = std::max(lambda / 4, 1e-7);
        improved = true;
        if (gain < 1e-7) it = 99;
      } else {
        lambda *= 8;
      }
    }
    if (!improved) break;
  }
  normalise_periodic(fit.params);
  fit.rss = weighted_residual(ctx, fit.params).squaredNorm();
}

namespace {

// 0 for joint j's samples from 20 ms before to 200 ms after a reversal of its
// command (where a friction spike acts and decays), 1 elsewhere; stacked as
// the weighted residual.
VectorXd away_from_reversals(const FitContext& ctx, int j) {
  const Trace& tr = *ctx.trace;
  const auto v = derivative(tr.t_s, tr.cmd[j]);
  std::vector<double> rev;
  double last = 0;
  for (std::size_t k = 0; k < v.size(); ++k) {
    if (v[k] == 0.0) continue;
    const double s = v[k] > 0 ? 1.0 : -1.0;
    if (last != 0 && s != last) rev.push_back(tr.t_s[k]);
    last = s;
  }
  VectorXd m = VectorXd::Ones(Eigen::Index(ctx.layout.size()));
  Eigen::Index r = 0;
  for (std::size_t a = 0; a < ctx.layout.axes.size(); ++a)
    for (std::size_t i = 0; i < ctx.layout.index[a].size(); ++i, ++r) {
      if (ctx.layout.axes[a] != j) continue;
      const double t = tr.t_s[ctx.layout.index[a][i]];
      const auto it = std::upper_bound(rev.begin(), rev.end(), t + 0.02);
      if (it != rev.begin() && t - *(it - 1) <= 0.2) m[r] = 0.0;
    }
  return m;
}

}  // namespace

void start_new_servo_loops(const FitContext& ctx, const std::vector<const Candidate*>& chosen,
                           const sim::MachineParams& before, sim::MachineParams& params) {
  // The pair is scanned on the model before the round with only the new
  // loops added: effects selected beside a loop in the same round were
  // fitted against its linear signature (feed-forward 0) and may stand in
  // for the loop's acceleration lag (a pitch or squareness term soaking up
  // the lag of a circle), which would make the wrong pair look best. The
  // other effects are kept for the fit that follows. The samples right
  // after the joint's reversals are left out of the scan: a friction spike
  // not yet in the model would pull the pair there.
  sim::MachineParams scan = before;
  for (const auto* c : chosen)
    if (c->effect == "servo_lag" && !before.effects.servo_lag.active(c->joint)) {
      scan.effects.servo_lag.enabled = true;
      scan.effects.servo_lag.axes[c->joint] = params.effects.servo_lag.axes[c->joint];
    }
  for (const auto* c : chosen) {
    if (c->effect != "servo_lag" || before.effects.servo_lag.active(c->joint)) continue;
    const VectorXd keep = away_from_reversals(ctx, c->joint);
    auto& a = *scan.effects.servo_lag.axes[c->joint];
    const double lag_s = (1.0 - a.ff1) / a.kv_per_s;
    sim::ServoLagAxis best = a;
    double best_rss = weighted_residual(ctx, scan).cwiseProduct(keep).squaredNorm();
    for (double ff1 : {0.0, 0.5, 0.8, 0.9, 0.95, 0.98, 0.99}) {
      sim::MachineParams p = scan;
      auto& b = *p.effects.servo_lag.axes[c->joint];
      b.ff1 = ff1;
      b.kv_per_s = clamp_param("kv_per_s", (1.0 - ff1) / lag_s);
      const double rr = weighted_residual(ctx, p).cwiseProduct(keep).squaredNorm();
      if (rr < best_rss) best_rss = rr, best = b;
    }
    a = best;
    *params.effects.servo_lag.axes[c->joint] = best;
  }
}

void restart_loops_with_friction(const FitContext& ctx, const std::vector<const Candidate*>& chosen,
                                 const sim::MachineParams& base, sim::MachineParams& params) {
  for (const auto* c : chosen) {
    const int j = c->joint;
    if (c->effect != "reversal_spike" || base.effects.servo_lag.active(j) ||
        !params.effects.servo_lag.active(j) || !params.effects.reversal_spike.active(j))
      continue;
    const std::string key = coulomb_key(j);
    const double lag_s =
        (1.0 - params.effects.servo_lag.axes[j]->ff1) / params.effects.servo_lag.axes[j]->kv_per_s;
    sim::MachineParams best = params;
    double best_rss = weighted_residual(ctx, params).squaredNorm();
    for (double ff1 : {0.0, 0.5, 0.8, 0.9, 0.95, 0.98, 0.99}) {
      sim::MachineParams p = params;
      auto& b = *p.effects.servo_lag.axes[j];
      b.ff1 = ff1;
      b.kv_per_s = clamp_param("kv_per_s", (1.0 - ff1) / lag_s);
      // The friction refitted at this pair: one Gauss-Newton step on F_c.
      double* f = param_ptr(p, "reversal_spike", j, key);
      const double f0 = *f, h = std::max(0.1 * f0, 1.0);
      const VectorXd r0 = weighted_residual(ctx, p);
      *f = f0 + h;
      const VectorXd col = (weighted_residual(ctx, p) - r0) / h;
      const double cc = col.squaredNorm();
      *f = cc > 0 ? std::max(f0 - col.dot(r0) / cc, 0.0) : f0;
      double rr = weighted_residual(ctx, p).squaredNorm();
      if (!(rr < r0.squaredNorm())) *f = f0, rr = r0.squaredNorm();
      if (rr < best_rss) best_rss = rr, best = p;
    }
    params = best;
  }
}

}  // namespace truecut::analysis::diagnosis
