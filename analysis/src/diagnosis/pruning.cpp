// Effects the re-simulated model does not need: each drop refits the others.
#include <algorithm>
#include <cmath>

#include "effect_params.hpp"
#include "fit_steps.hpp"

namespace truecut::analysis::diagnosis {

using Eigen::MatrixXd;
using Eigen::VectorXd;

sim::MachineParams without_effect(const sim::MachineParams& fitted,
                                  const sim::MachineParams& reference, const SelectedEffect& s) {
  sim::MachineParams p = fitted;
  sim::MachineParams b = reference;
  bool had = true;
  for (const auto& k : s.keys)
    had = had && param_ptr(b, s.effect, s.joint, k) != nullptr;
  if (s.effect == "straightness") {
    auto& comps = p.effects.straightness.params.components;
    for (int i = 0; i < sim::kStraightnessCount; ++i)
      if (s.axis == sim::kStraightnessNames[i])
        comps[i] = b.effects.straightness.params.components[i];
    p.effects.straightness.enabled =
        std::any_of(comps.begin(), comps.end(), [](const auto& c) { return bool(c); });
    return p;
  }
  if (s.effect == "squareness" || s.effect == "pitch_error" || had) {
    for (const auto& k : s.keys) {
      double* v = param_ptr(p, s.effect, s.joint, k);
      const double* bv = param_ptr(b, s.effect, s.joint, k);
      if (v) *v = bv ? *bv : (k == "periodic_period_mm" ? *v : 0.0);
    }
    return p;
  }
  disable_effect(p, s.effect, s.joint);
  return p;
}

namespace {

void say(const FitContext& ctx, const std::string& s) {
  if (ctx.progress) ctx.progress(s);
}

// Drops fit.selected[e] (back to `base`) and refits the others.
void drop_effect(const FitContext& ctx, const sim::MachineParams& base, std::size_t e,
                 ModelFit& fit) {
  fit.params = without_effect(fit.params, base, fit.selected[e]);
  fit.selected.erase(fit.selected.begin() + std::ptrdiff_t(e));
  refine(ctx, fit);
}

}  // namespace

std::vector<std::string> drop_slopes_taken_for_bows(const FitContext& ctx,
                                                    const sim::MachineParams& base, ModelFit& fit) {
  std::vector<std::string> dropped;
  for (std::size_t e = 0; e < fit.selected.size();) {
    const SelectedEffect& s = fit.selected[e];
    int i = -1;
    for (int c = 0; c < sim::kStraightnessCount && s.effect == "straightness"; ++c)
      if (s.axis == sim::kStraightnessNames[c]) i = c;
    const auto& comp = i >= 0 ? fit.params.effects.straightness.params.components[i] : std::nullopt;
    const auto& cmd = i >= 0 ? ctx.trace->cmd[sim::kStraightnessMoving[i]] : std::vector<double>{};
    if (!comp || cmd.empty()) {
      ++e;
      continue;
    }
    const auto [lo, hi] = std::minmax_element(cmd.begin(), cmd.end());
    const double span = *hi - *lo;
    if (comp->reference_mm >= *lo - span && comp->reference_mm <= *hi + span) {
      ++e;
      continue;
    }
    say(ctx,
        "dropped " + s.group + ": its flat point went outside the travel (a slope, not a bow)");
    dropped.push_back(s.group);
    drop_effect(ctx, base, e, fit);
  }
  return dropped;
}

std::vector<std::string> drop_offsets_taken_for_drifts(const FitContext& ctx,
                                                       const sim::MachineParams& base,
                                                       ModelFit& fit) {
  std::vector<std::string> dropped;
  const Trace& tr = *ctx.trace;
  for (std::size_t e = 0; e < fit.selected.size();) {
    const SelectedEffect& s = fit.selected[e];
    const auto* th =
        s.effect == "thermal_drift" ? fit.params.effects.thermal_drift.active(s.joint) : nullptr;
    double t_first = INFINITY;
    for (std::size_t a = 0; a < ctx.layout.axes.size(); ++a)
      if (ctx.layout.axes[a] == s.joint && !ctx.layout.index[a].empty())
        t_first = tr.t_s[ctx.layout.index[a].front()] - tr.t_s.front();
    if (!th || th->driver != sim::ThermalDriver::kTime || !(th->tau_s < t_first / 3)) {
      ++e;
      continue;
    }
    say(ctx, "dropped " + s.group +
                 ": its time constant went below a third of the time to the "
                 "first fitted sample (an offset, not a drift)");
    dropped.push_back(s.group);
    drop_effect(ctx, base, e, fit);
  }
  return dropped;
}

// Backward elimination: an effect selected on the linearisation that the
// re-simulated model does not need any more (it stood in for a
// linearisation error of another one) is dropped.
std::vector<std::string> drop_unneeded(const FitContext& ctx, const sim::MachineParams& base,
                                       double n_eff, ModelFit& fit) {
  std::vector<std::string> dropped;
  for (;;) {
    std::size_t weakest = fit.selected.size();
    double weakest_cost = INFINITY;
    for (std::size_t i = 0; i < fit.selected.size(); ++i) {
      const sim::MachineParams p = without_effect(fit.params, base, fit.selected[i]);
      const double rr = weighted_residual(ctx, p).squaredNorm();
      const double cost = n_eff * std::log(std::max(rr, 1e-300) / std::max(fit.rss, 1e-300)) -
                          double(fit.selected[i].keys.size()) * std::log(n_eff);
      if (cost < weakest_cost) weakest_cost = cost, weakest = i;
    }
    if (weakest == fit.selected.size() || weakest_cost >= ctx.bic_threshold) break;
    say(ctx, "dropped " + fit.selected[weakest].group + " (re-simulated ΔBIC " +
                 fmt4g(-weakest_cost) + ")");
    dropped.push_back(fit.selected[weakest].group);
    // The others were fitted beside it: fit them again without it.
    drop_effect(ctx, base, weakest, fit);
  }
  return dropped;
}

std::vector<std::string> drop_stand_ins_for_splits(const FitContext& ctx,
                                                   const sim::MachineParams& base, double n_eff,
                                                   ModelFit& fit) {
  std::vector<std::string> dropped;
  FitContext quiet = ctx;  // the trials' splits are not reported
  quiet.progress = nullptr;
  fit.rss = weighted_residual(ctx, fit.params).squaredNorm();
  for (bool again = true; again;) {
    again = false;
    for (std::size_t e = 0; e < fit.selected.size() && !again; ++e) {
      const SelectedEffect& s = fit.selected[e];
      if (s.effect == "servo_lag") continue;
      ModelFit trial = fit;
      trial.params = without_effect(fit.params, base, s);
      trial.selected.erase(trial.selected.begin() + std::ptrdiff_t(e));
      // Only where a split moves without it: otherwise drop_unneeded judged it.
      if (!refine_servo_splits(quiet, trial)) continue;
      const double cost =
          n_eff * std::log(std::max(trial.rss, 1e-300) / std::max(fit.rss, 1e-300)) -
          double(s.keys.size()) * std::log(n_eff);
      if (cost >= ctx.bic_threshold) {
        say(ctx, "kept " + s.group + ": with the splits refined without it the model costs " +
                     fmt4g(cost) + " in BIC");
        continue;
      }
      say(ctx, "dropped " + s.group + ": it stood in for a servo loop's split (re-simulated ΔBIC " +
                   fmt4g(-cost) + " with the splits refined without it)");
      dropped.push_back(s.group);
      fit = std::move(trial);
      again = true;
    }
  }
  return dropped;
}

// An adjustment of an effect the believed model already has is kept only
// when the data move it: when the 95 % interval of every one of its
// parameters still covers the believed value, the believed value stands.
void drop_believed_within_interval(const FitContext& ctx, const sim::MachineParams& base,
                                   ModelFit& fit) {
  for (bool dropped = true; dropped && !fit.selected.empty();) {
    dropped = false;
    const auto ks = keys_of(fit.selected);
    const VectorXd rr = weighted_residual(ctx, fit.params);
    const VectorXd t0 = get_theta(fit.params, ks);
    const MatrixXd J = jacobian(ctx, fit.params, ks, t0, rr);
    const MatrixXd cv = parameter_covariance(ctx.layout, J, rr);
    Eigen::Index i = 0;
    for (std::size_t e = 0; e < fit.selected.size() && !dropped; ++e) {
      const auto& sel = fit.selected[e];
      sim::MachineParams b = base;
      bool covered = true;
      for (const auto& k : sel.keys) {
        const double* bv = param_ptr(b, sel.effect, sel.joint, k);
        const double se = std::sqrt(std::max(0.0, cv(i, i)));
        covered = covered && bv && std::abs(t0[i] - *bv) <= 1.96 * se;
        ++i;
      }
      if (!covered) continue;
      say(ctx, "dropped " + sel.group + ": the believed value lies inside the fitted interval");
      drop_effect(ctx, base, e, fit);
      dropped = true;
    }
  }
}

// Too small to matter, re-simulated: an effect (or an adjustment of a
// believed one) whose contribution stays below min_effect_ratio of the
// noise floor is not claimed, however strongly the BIC favours it (with
// noise-free or quantised data the BIC sees any systematic misfit).
void drop_too_small(const FitContext& ctx, const sim::MachineParams& base, ModelFit& fit) {
  for (bool dropped = true; dropped && !fit.selected.empty();) {
    dropped = false;
    const VectorXd r_fit = weighted_residual(ctx, fit.params);
    std::size_t smallest = 0;
    double smallest_rms = INFINITY, smallest_share = INFINITY;
    for (std::size_t e = 0; e < fit.selected.size(); ++e) {
      const VectorXd diff =
          weighted_residual(ctx, without_effect(fit.params, base, fit.selected[e])) - r_fit;
      const double rms = rms_on_support(diff, ctx.layout);
      const double share = rms / fit.selected[e].min_effect_ratio;
      if (share < smallest_share) smallest_share = share, smallest_rms = rms, smallest = e;
    }
    if (smallest_share >= 1.0) break;
    say(ctx, "dropped " + fit.selected[smallest].group + ": its contribution is " +
                 fmt4g(smallest_rms) + " of the noise floor");
    drop_effect(ctx, base, smallest, fit);
    dropped = true;
  }
}

}  // namespace truecut::analysis::diagnosis
