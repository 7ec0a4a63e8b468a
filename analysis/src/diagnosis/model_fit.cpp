// The model fit as a sequence of steps: rounds of (signatures → selection
// by BIC → nonlinear fit → backward elimination), then the pruning of what
// the data do not support, held-out confirmation and the intervals. The
// steps live in the files fit_steps.hpp lists.
#include "model_fit.hpp"

#include <algorithm>
#include <cmath>
#include <set>

#include "fit_steps.hpp"

namespace truecut::analysis::diagnosis {

using Eigen::VectorXd;

namespace {

void say(const FitContext& ctx, const std::string& s) {
  if (ctx.progress) ctx.progress(s);
}

// The candidates of groups not yet selected; each candidate's name is
// added to fit.tested on first sight.
std::vector<Candidate> open_candidates(std::vector<Candidate> cands,
                                       const std::set<std::string>& have, ModelFit& fit) {
  std::vector<Candidate> open;
  for (auto& c : cands) {
    if (have.count(c.group)) continue;
    const std::string name = c.effect + (c.axis.empty() ? "" : ":" + c.axis);
    if (std::find(fit.tested.begin(), fit.tested.end(), name) == fit.tested.end())
      fit.tested.push_back(name);
    open.push_back(std::move(c));
  }
  return open;
}

void add_confusions(const std::vector<NotIdentifiable>& found, ModelFit& fit) {
  for (const auto& ni : found) {
    bool dup = false;
    for (const auto& e : fit.not_identifiable)
      dup = dup || (e.first == ni.first && e.second == ni.second);
    if (!dup) fit.not_identifiable.push_back(ni);
  }
}

// Puts the chosen effects into fit.params from their linear coefficients.
void apply_selection(const FitContext& ctx, const Selection& sel, std::set<std::string>& have,
                     ModelFit& fit) {
  Eigen::Index c0 = 0;
  for (std::size_t i = 0; i < sel.chosen.size(); ++i) {
    const Candidate* c = sel.chosen[i];
    c->apply(fit.params, sel.coef.segment(c0, c->X.cols()));
    c0 += c->X.cols();
    fit.selected.push_back({c->effect, c->joint, c->axis, c->group, c->variant, c->keys,
                            sel.delta_bic[i],
                            c->min_effect_ratio > 0 ? c->min_effect_ratio : ctx.min_effect_ratio});
    have.insert(c->group);
    say(ctx, "selected " + c->label() + " (ΔBIC " + fmt4g(sel.delta_bic[i]) + ")");
  }
  normalise_periodic(fit.params);
}

// One round; false when it ends the rounds (nothing selected, or the
// re-simulation does not confirm the round, whose effects are then undone).
bool fit_round(const FitContext& ctx, const sim::MachineParams& base, int round,
               std::set<std::string>& have, ModelFit& fit) {
  const VectorXd r = weighted_residual(ctx, fit.params);
  std::vector<Candidate> open = open_candidates(build_candidates(ctx, fit.params), have, fit);
  double n_eff = 0;
  const Selection sel = forward_select(open, r, ctx.bic_threshold, ctx.min_effect_ratio, ctx.layout,
                                       fit.params, n_eff);
  add_confusions(sel.confusions, fit);
  if (sel.chosen.empty()) return false;
  const ModelFit before_round = fit;
  const double rss_before_round = r.squaredNorm();
  apply_selection(ctx, sel, have, fit);
  start_new_servo_loops(ctx, sel.chosen, before_round.params, fit.params);
  restart_loops_with_friction(ctx, sel.chosen, base, fit.params);

  // Nonlinear fit of every selected parameter by re-simulation.
  refine(ctx, fit);
  refine_servo_splits(ctx, fit);
  drop_slopes_taken_for_bows(ctx, base, fit);  // kept in `have`: not offered again
  drop_offsets_taken_for_drifts(ctx, base, fit);
  const Eigen::Index m = Eigen::Index(keys_of(fit.selected).size());
  // Verified by re-simulation: the round's effects must pay for their
  // parameters in the real model too, not only in the linearisation.
  const int added = int(m) - int(keys_of(before_round.selected).size());
  const double gain =
      n_eff * std::log(std::max(fit.rss, 1e-300) / rss_before_round) + added * std::log(n_eff);
  say(ctx, "fitted " + std::to_string(m) + " parameters by re-simulation, round " +
               std::to_string(round + 1) + " (ΔBIC " + fmt4g(gain) + ")");
  for (const auto& g : drop_unneeded(ctx, base, n_eff, fit))
    have.erase(g);
  // The refits of the backward elimination move the others' parameters:
  // the slope and offset rules hold on the model that stays.
  drop_slopes_taken_for_bows(ctx, base, fit);
  drop_offsets_taken_for_drifts(ctx, base, fit);
  if (gain > -ctx.bic_threshold || fit.selected.empty()) {
    say(ctx, "re-simulation does not confirm the round's effects; dropped");
    auto tested = fit.tested;
    auto confusions = fit.not_identifiable;
    fit = before_round;
    fit.tested = tested;
    fit.not_identifiable = confusions;
    return false;
  }
  return true;
}

// The splits of the servo loops once more, on the model that stays: the
// rounds refined them beside terms that stood in for effects not yet in the
// model (a friction that a later round brings in) or for the wrong split
// itself (pitch scales taking up part of the lag), which the elimination
// dropped afterwards; the split they pulled stayed, since
// Levenberg–Marquardt does not travel the valley. What a moved split no
// longer needs is eliminated again, and the splits refined once more
// when something went. Last, an effect that stands in for a split the
// refinement cannot leave beside it (the two pulled each other) is dropped
// when the splits refined without it fit as well (drop_stand_ins_for_splits),
// and what the model then no longer needs is eliminated once more.
void refine_splits_of_final_model(const FitContext& ctx, const sim::MachineParams& base,
                                  ModelFit& fit) {
  auto n_eff = [&] {
    return n_eff_of(double(fit.n), ctx.layout.lag1(weighted_residual(ctx, fit.params)));
  };
  for (int pass = 0; pass < 3 && refine_servo_splits(ctx, fit); ++pass) {
    const std::size_t had = fit.selected.size();
    drop_unneeded(ctx, base, n_eff(), fit);
    drop_too_small(ctx, base, fit);
    if (fit.selected.size() == had) break;
  }
  // What only the stand-ins held up goes with them (on circles a
  // straightness exy of −11 µm/m², interval ±37, stayed beside pitch terms
  // that stood in for the split).
  if (!drop_stand_ins_for_splits(ctx, base, n_eff(), fit).empty()) {
    drop_unneeded(ctx, base, n_eff(), fit);
    drop_too_small(ctx, base, fit);
  }
}

}  // namespace

ModelFit fit_model(const FitContext& ctx, const sim::MachineParams& base) {
  ModelFit fit;
  fit.params = base;
  fit.n = ctx.layout.size();
  std::set<std::string> have;
  for (int round = 0; round < 3; ++round)
    if (!fit_round(ctx, base, round, have, fit)) break;
  drop_believed_within_interval(ctx, base, fit);
  drop_too_small(ctx, base, fit);
  confirm_on_heldout(ctx, base, fit);
  refine_splits_of_final_model(ctx, base, fit);
  drop_slopes_taken_for_bows(ctx, base, fit);
  drop_offsets_taken_for_drifts(ctx, base, fit);
  // Confusions found on the linearisation count only for effects that stayed.
  std::erase_if(fit.not_identifiable, [&](const NotIdentifiable& ni) {
    return std::none_of(fit.selected.begin(), fit.selected.end(),
                        [&](const SelectedEffect& s) { return s.group == ni.first; });
  });
  report_intervals(ctx, fit);
  widen_split_intervals(ctx, fit);
  return fit;
}

}  // namespace truecut::analysis::diagnosis
