// Proof on data the fit did not see: an effect that raises the held-out
// residual is not confirmed.
#include <algorithm>
#include <cmath>

#include "fit_steps.hpp"

namespace truecut::analysis::diagnosis {

double heldout_rss(const FitContext& ctx, const sim::MachineParams& p) {
  using Targets = std::array<std::vector<double>, sim::kJointCount>;
  const Targets tt = simulate_aligned_targets(ctx, p);
  const Targets th =
      ctx.heldout->trace == ctx.trace ? Targets() : simulate_aligned_targets(*ctx.heldout, p);
  const Targets& ht = ctx.heldout->trace == ctx.trace ? tt : th;
  const Layout& tl = ctx.layout;
  const Layout& hl = ctx.heldout->layout;
  double rss = 0;
  for (std::size_t a = 0; a < tl.axes.size(); ++a) {
    const int j = tl.axes[a];
    double off = 0, uu = 0;
    for (std::size_t i = 0; i < tl.index[a].size(); ++i) {
      const std::size_t k = tl.index[a][i];
      const double u2 = tl.w(a, i) * tl.w(a, i);
      off += u2 * (ctx.aligned[j][k] - tt[j][k]), uu += u2;
    }
    off = uu > 0 ? off / uu : 0.0;
    for (std::size_t i = 0; i < hl.index[a].size(); ++i) {
      const std::size_t k = hl.index[a][i];
      const double r = (ctx.heldout->aligned[j][k] - ht[j][k] - off) * hl.w(a, i);
      rss += r * r;
    }
  }
  return rss;
}

namespace {

// An RMS in mm for the report: the weighted RSS over the sum of squared weights.
double heldout_rms_mm(const FitContext& ctx, double rss) {
  const Layout& hl = ctx.heldout->layout;
  double ww = 0;
  for (std::size_t a = 0; a < hl.index.size(); ++a)
    for (std::size_t i = 0; i < hl.index[a].size(); ++i)
      ww += hl.w(a, i) * hl.w(a, i);
  return ww > 0 ? std::sqrt(rss / ww) : 0.0;
}

}  // namespace

// The fitted model against the same model without each effect; the
// others are fitted again without the one dropped.
void confirm_on_heldout(const FitContext& ctx, const sim::MachineParams& base, ModelFit& fit) {
  if (!ctx.heldout) return;
  const double none = heldout_rss(ctx, base);
  for (bool dropped = true; dropped && !fit.selected.empty();) {
    dropped = false;
    const double with = heldout_rss(ctx, fit.params);
    std::size_t worst = 0;
    double worst_gain = INFINITY, worst_without = 0;
    for (std::size_t e = 0; e < fit.selected.size(); ++e) {
      const double without = heldout_rss(ctx, without_effect(fit.params, base, fit.selected[e]));
      if (without - with < worst_gain)
        worst_gain = without - with, worst = e, worst_without = without;
    }
    // About zero: the held-out data do not see the effect (e.g. no
    // reversal of that axis there); they neither confirm nor refute it.
    // Effects that help each other to a worse prediction than the
    // believed model are dropped too, the least useful first.
    if (worst_gain >= -1e-9 * with && with <= none * (1 + 1e-9)) break;
    const auto& sel = fit.selected[worst];
    if (ctx.progress)
      ctx.progress("dropped " + sel.group + ": the held-out residual does not confirm it");
    fit.not_confirmed.push_back(
        {sel.effect, sel.axis, heldout_rms_mm(ctx, with), heldout_rms_mm(ctx, worst_without)});
    fit.params = without_effect(fit.params, base, sel);
    fit.selected.erase(fit.selected.begin() + std::ptrdiff_t(worst));
    refine(ctx, fit);
    dropped = true;
  }
}

}  // namespace truecut::analysis::diagnosis
