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

namespace {

// The profile of a servo loop's split along its valley of equal steady lag:
// ff1 moved with Kv = (1 − ff1) / lag, every other fitted parameter (the
// loop's Kv among them, so that the lag may settle too) taken by one linear
// step on the Jacobian of the starting point.
class SplitProfile {
 public:
  SplitProfile(const FitContext& ctx, const ModelFit& fit, std::size_t ff1_index)
      : ctx_(ctx), params_(fit.params) {
    const auto keys = keys_of(fit.selected);
    joint_ = keys[ff1_index].joint;
    const auto& a = *params_.effects.servo_lag.axes[joint_];
    lag_s_ = (1.0 - a.ff1) / a.kv_per_s;
    ff1_ = a.ff1;
    for (std::size_t k = 0; k < keys.size(); ++k)
      if (k != ff1_index) others_.push_back(keys[k]);
    keep_ = away_from_reversals(ctx_, joint_);
    const VectorXd r0 = weighted_residual(ctx_, params_);
    rss0_ = r0.squaredNorm();
    theta_others_ = get_theta(params_, others_);
    if (!others_.empty()) {
      J_ = keep_.asDiagonal() * jacobian(ctx_, params_, others_, theta_others_, r0);
      qr_.setThreshold(1e-10);
      qr_.compute(J_);
    }
  }
  double ff1() const { return ff1_; }
  double lag_s() const { return lag_s_; }
  double rss0() const { return rss0_; }
  int joint() const { return joint_; }
  // The model at split ff1 with the others' linear step (the residual it
  // leaves, linearised, in *left).
  sim::MachineParams at(double ff1, VectorXd* left = nullptr, bool step_others = true) const {
    sim::MachineParams p = params_;
    auto& a = *p.effects.servo_lag.axes[joint_];
    a.ff1 = clamp_param("ff1", ff1);
    a.kv_per_s = clamp_param("kv_per_s", (1.0 - a.ff1) / lag_s_);
    const VectorXd r = weighted_residual(ctx_, p).cwiseProduct(keep_);
    if (others_.empty() || (!left && !step_others)) {
      if (left) *left = r;
      return p;
    }
    const VectorXd c = qr_.solve(r);
    if (left) *left = r - J_ * c;
    const double split = a.ff1;
    set_theta(p, others_, get_theta(p, others_) - c);  // residual r(θ + δ) ≈ r + J δ
    p.effects.servo_lag.axes[joint_]->ff1 = split;
    return p;
  }
  double rss(double ff1) const {
    VectorXd left;
    at(ff1, &left);
    return left.squaredNorm();
  }

 private:
  const FitContext& ctx_;
  sim::MachineParams params_;
  std::vector<Key> others_;
  int joint_ = 0;
  double lag_s_ = 0.0, ff1_ = 0.0, rss0_ = 0.0;
  VectorXd theta_others_, keep_;
  MatrixXd J_;
  Eigen::ColPivHouseholderQR<MatrixXd> qr_;
};

// The ff1 minimising f between the points of the start's grid
// (start_new_servo_loops) on either side of `start`: a finer grid there,
// then golden section between the neighbours of its best point. The move
// stays within one step of the start's grid: far along the valley an
// effect not yet in the model (a friction spike, a backlash) would pull
// the split, as it pulled the start before the grid was scanned with the
// reversals left out.
template <class F>
double minimise_split(const F& f, double start, double& best_f) {
  const double coarse[] = {0.0, 0.5, 0.8, 0.9, 0.95, 0.98, 0.99};
  double lo = start, hi = 0.999;
  for (double g : coarse) {
    if (g < start - 1e-3) lo = g;
    if (g > start + 1e-3 && hi == 0.999) hi = g;
  }
  std::vector<double> grid;
  for (int i = 0; i <= 6; ++i)
    grid.push_back(lo + (hi - lo) * i / 6.0);
  std::vector<double> val(grid.size());
  std::size_t b = 0;
  for (std::size_t i = 0; i < grid.size(); ++i) {
    val[i] = f(grid[i]);
    if (val[i] < val[b]) b = i;
  }
  lo = grid[b > 0 ? b - 1 : b], hi = grid[b + 1 < grid.size() ? b + 1 : b];
  const double g = (std::sqrt(5.0) - 1.0) / 2.0;
  double c = hi - g * (hi - lo), d = lo + g * (hi - lo);
  double fc = f(c), fd = f(d);
  for (int it = 0; it < 14 && hi - lo > 2e-4; ++it) {
    if (fc < fd) {
      hi = d, d = c, fd = fc;
      c = hi - g * (hi - lo), fc = f(c);
    } else {
      lo = c, c = d, fc = fd;
      d = lo + g * (hi - lo), fd = f(d);
    }
  }
  double x = grid[b];
  best_f = val[b];
  if (fc < best_f) x = c, best_f = fc;
  if (fd < best_f) x = d, best_f = fd;
  return x;
}

}  // namespace

bool refine_servo_splits(const FitContext& ctx, ModelFit& fit) {
  bool moved = false;
  for (std::size_t e = 0; e < fit.selected.size(); ++e) {
    const SelectedEffect& s = fit.selected[e];
    if (s.effect != "servo_lag" || !fit.params.effects.servo_lag.active(s.joint)) continue;
    const auto keys = keys_of(fit.selected);
    std::size_t i = keys.size();
    for (std::size_t k = 0; k < keys.size(); ++k)
      if (keys[k].effect == "servo_lag" && keys[k].joint == s.joint && keys[k].key == "ff1") i = k;
    if (i == keys.size()) continue;
    const SplitProfile prof(ctx, fit, i);
    double best = 0;
    const double ff1 = minimise_split([&](double f) { return prof.rss(f); }, prof.ff1(), best);
    if (!(best < prof.rss(prof.ff1()) * (1 - 1e-6))) continue;
    ModelFit trial = fit;
    // The others' linear step is a start only: on a nonlinear term (a
    // periodic pitch's period, a drift's τ) it may overshoot far, so the
    // split alone is tried too, and the better of the two refitted from.
    trial.params = prof.at(ff1);
    normalise_periodic(trial.params);
    const sim::MachineParams alone = prof.at(ff1, nullptr, false);
    if (!(weighted_residual(ctx, trial.params).squaredNorm() <
          weighted_residual(ctx, alone).squaredNorm()))
      trial.params = alone;
    refine(ctx, trial);
    if (!(trial.rss < prof.rss0())) continue;
    const auto& a = *trial.params.effects.servo_lag.axes[s.joint];
    if (ctx.progress)
      ctx.progress("servo loop " + std::string(sim::kJointNames[s.joint]) +
                   ": split moved along its steady lag to Kv " + fmt4g(a.kv_per_s) + ", ff1 " +
                   fmt4g(a.ff1));
    fit = std::move(trial);
    moved = true;
  }
  return moved;
}

void widen_split_intervals(const FitContext& ctx, ModelFit& fit) {
  const auto keys = keys_of(fit.selected);
  const VectorXd r0 = weighted_residual(ctx, fit.params);
  const double rho = std::clamp(ctx.layout.lag1(r0), 0.0, 0.99);
  for (std::size_t i = 0; i < keys.size(); ++i) {
    if (keys[i].effect != "servo_lag" || keys[i].key != "ff1") continue;
    const int j = keys[i].joint;
    std::size_t ikv = keys.size();
    for (std::size_t k = 0; k < keys.size(); ++k)
      if (keys[k].effect == "servo_lag" && keys[k].joint == j && keys[k].key == "kv_per_s") ikv = k;
    if (ikv == keys.size() || !fit.params.effects.servo_lag.active(j)) continue;
    const SplitProfile prof(ctx, fit, i);
    const double f0 = prof.ff1(), rss_min = prof.rss(f0);
    double used = 0;
    for (const auto& ix : ctx.layout.index)
      used += double(ix.size());
    const double var = rss_min / std::max(1.0, used - double(keys.size())) * (1 + rho) / (1 - rho);
    auto chi2 = [&](double f) { return (prof.rss(f) - rss_min) / var; };
    // The ff1 on one side where the profile rises by 3.84 (95 %), or the
    // end of the range.
    auto edge = [&](double dir) {
      const double end = dir < 0 ? 0.0 : 0.999;
      double in = f0, out = f0;
      bool found = false;
      for (double d = 1e-3; !found; d *= 2) {
        out = std::clamp(f0 + dir * d, 0.0, 0.999);
        if (chi2(out) > 3.84)
          found = true;
        else
          in = out;
        if (out == end) break;
      }
      if (!found) return end;
      for (int it = 0; it < 8; ++it) {
        const double m = (in + out) / 2;
        (chi2(m) > 3.84 ? out : in) = m;
      }
      return (in + out) / 2;
    };
    const double lo = edge(-1), hi = edge(+1);
    const double kv_hi = (1.0 - lo) / prof.lag_s(), kv_lo = (1.0 - hi) / prof.lag_s();
    auto widen = [&](std::size_t k, double a, double b) {
      Parameter& p = fit.parameters[k];
      p.ci95_lo = std::min(p.ci95_lo, a);
      p.ci95_hi = std::max(p.ci95_hi, b);
    };
    if (fit.parameters.size() != keys.size()) continue;
    widen(i, lo, hi);
    widen(ikv, kv_lo, kv_hi);
    // The per-effect copy.
    std::size_t k = 0;
    for (auto& e : fit.per_effect)
      for (auto& p : e) {
        if (k == i || k == ikv) p = fit.parameters[k];
        ++k;
      }
    if (ctx.progress)
      ctx.progress("servo loop " + std::string(sim::kJointNames[j]) +
                   ": split along its steady lag within ff1 " + fmt4g(lo) + " .. " + fmt4g(hi) +
                   ", Kv " + fmt4g(kv_lo) + " .. " + fmt4g(kv_hi) + " (profile, 95 %)");
  }
}

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
