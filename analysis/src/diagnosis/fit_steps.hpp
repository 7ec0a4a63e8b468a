// The steps of the model fit (model_fit.hpp), each in its own file:
//   fit_residual.cpp   the weighted residual, the parameter vector, its Jacobian
//   candidates.cpp     the linearised signatures of the candidate effects
//   bic_selection.cpp  forward selection by BIC on the linearisation
//   refine.cpp         Levenberg–Marquardt by re-simulation
//   pruning.cpp        effects the re-simulated model does not need
//   heldout.cpp        confirmation on held-out data
//   confidence.cpp     parameter covariance and confidence intervals
//   model_fit.cpp      the rounds that chain them
#pragma once

#include <string>
#include <vector>

#include "model_fit.hpp"

namespace truecut::analysis::diagnosis {

// "%.4g".
std::string fmt4g(double v);

// The residual sum of squares of `r` after least squares on the columns of X
// (the coefficients in *coef when given).
double rss_after(const Eigen::MatrixXd& X, const Eigen::VectorXd& r,
                 Eigen::VectorXd* coef = nullptr);
// The columns of every part side by side.
Eigen::MatrixXd hcat(const std::vector<const Eigen::MatrixXd*>& parts, Eigen::Index rows);
// Effective sample count of n samples with lag-1 autocorrelation rho
// (clamped to [0, 0.99]): n (1 − ρ) / (1 + ρ), at least 2.
double n_eff_of(double n, double rho);

// One fitted parameter: an effect's key on a joint.
struct Key {
  std::string effect;
  int joint;
  std::string key;
};
std::vector<Key> keys_of(const std::vector<SelectedEffect>& sel);
void set_theta(sim::MachineParams& p, const std::vector<Key>& keys, const Eigen::VectorXd& th);
Eigen::VectorXd get_theta(sim::MachineParams& p, const std::vector<Key>& keys);
// Periodic pitch error: amplitude kept positive, phase in (−180, 180].
void normalise_periodic(sim::MachineParams& p);
// Forward-difference Jacobian of the weighted residual in `keys` at theta
// (r0: the residual there), one re-simulation per parameter.
Eigen::MatrixXd jacobian(const FitContext& ctx, const sim::MachineParams& params,
                         const std::vector<Key>& keys, const Eigen::VectorXd& theta,
                         const Eigen::VectorXd& r0);

// The RMS of a stacked vector over the axes it touches (those with at
// least 1 % of the largest axis' RMS).
double rms_on_support(const Eigen::VectorXd& v, const Layout& layout);

struct Selection {
  std::vector<const Candidate*> chosen;
  std::vector<double> delta_bic;
  Eigen::VectorXd coef;  // joint fit, columns in the order of chosen
  std::vector<NotIdentifiable> confusions;
};

// Forward selection over the candidates' groups by BIC on the residual r
// (among a group's variants the best one); n_eff_out: the effective sample
// count used.
Selection forward_select(const std::vector<Candidate>& cands, const Eigen::VectorXd& r,
                         double threshold, double min_effect, const Layout& layout,
                         const sim::MachineParams& base, double& n_eff_out);

// Levenberg–Marquardt on every parameter of fit.selected by re-simulation
// (numeric Jacobian, at most 12 iterations); updates fit.params and fit.rss.
void refine(const FitContext& ctx, ModelFit& fit);

// Each selected servo loop's split (Kv, ff1) moved along its valley of
// equal steady lag (1 − ff1)/Kv to the best of the profile in which every
// other fitted parameter follows by a linear step: Levenberg–Marquardt
// does not travel that valley from a grid point of the start, and other
// terms (a pitch scale) take up what the split leaves. Runs after each
// round's fit (so that none of the round's effects missing pulls the
// split) and once more on the model that stays after the rounds and the
// pruning (fit_model); the move is kept when the refit lowers the
// residual. True when a loop moved.
bool refine_servo_splits(const FitContext& ctx, ModelFit& fit);

// The 95 % intervals of each selected loop's Kv and ff1 widened to the
// profile along its valley of equal lag (where the profile of
// refine_servo_splits rises by 3.84 residual variances, inflated for
// correlated residuals): the Jacobian's interval at the estimate holds for
// a quadratic valley only, and the split is often far less determined than
// it says.
void widen_split_intervals(const FitContext& ctx, ModelFit& fit);

// A servo loop new to the model (selected this round, absent in `before`):
// the linear signature gives only the steady lag (1 − ff1)/Kv; the pair
// (Kv, ff1) with that lag that fits best by re-simulation is kept.
void start_new_servo_loops(const FitContext& ctx, const std::vector<const Candidate*>& chosen,
                           const sim::MachineParams& before, sim::MachineParams& params);

// A friction (reversal_spike) selected this round on a joint whose servo
// loop the diagnosis found itself (absent in `base`): the loop's pair was
// fitted without the friction and may have bent to mimic its spikes; the
// pair is scanned again along the same steady lag with the friction
// refitted at each, the best kept.
void restart_loops_with_friction(const FitContext& ctx, const std::vector<const Candidate*>& chosen,
                                 const sim::MachineParams& base, sim::MachineParams& params);

// A straightness whose flat point the re-simulated fit moved outside the
// candidate's range (the moving axis' travel ± its span) is a slope: a
// squareness or alignment, not a bow. It is dropped (and the rest refitted)
// so that a later round can offer the squareness; returns the groups.
std::vector<std::string> drop_slopes_taken_for_bows(const FitContext& ctx,
                                                    const sim::MachineParams& base, ModelFit& fit);

// A thermal drift driven by time whose time constant the re-simulated fit
// drove below a third of the time to the joint's first fitted sample has
// risen by 95 % before the data begin: an offset of the axis, which is
// profiled out, not a drift — except that it shifts the position that a
// straightness or squareness of another axis reads (with a bow of x over y
// it made a slope: a squareness). It is dropped (the rest refitted);
// returns the groups.
std::vector<std::string> drop_offsets_taken_for_drifts(const FitContext& ctx,
                                                       const sim::MachineParams& base,
                                                       ModelFit& fit);

// Pruning of fit.selected against `base`, each refitting the rest after a
// drop: effects whose re-simulated ΔBIC is below the threshold (returns the
// groups dropped), adjustments whose 95 % interval covers the believed
// value, and effects whose contribution stays below their min_effect_ratio
// of the noise floor.
std::vector<std::string> drop_unneeded(const FitContext& ctx, const sim::MachineParams& base,
                                       double n_eff, ModelFit& fit);
// Backward elimination with the servo loops' splits refined: an effect that
// stands in for a wrong split (a pitch scale of Z beside Z's loop at Kv 77 /
// ff1 0.81 for 40 / 0.9) costs much when dropped alone, the split staying
// where the two pulled it; it is dropped when, without it, a split moves
// (refine_servo_splits) and the model costs less than the threshold.
// Returns the groups dropped.
std::vector<std::string> drop_stand_ins_for_splits(const FitContext& ctx,
                                                   const sim::MachineParams& base, double n_eff,
                                                   ModelFit& fit);
void drop_believed_within_interval(const FitContext& ctx, const sim::MachineParams& base,
                                   ModelFit& fit);
void drop_too_small(const FitContext& ctx, const sim::MachineParams& base, ModelFit& fit);

// Weighted held-out RSS of `p` (offsets from the fitted block, as a
// prediction must carry them); ctx.heldout must be set.
double heldout_rss(const FitContext& ctx, const sim::MachineParams& p);
// Drops (into fit.not_confirmed) the effects the held-out residual does not
// confirm; nothing without ctx.heldout.
void confirm_on_heldout(const FitContext& ctx, const sim::MachineParams& base, ModelFit& fit);

// Covariance of the parameters from the Jacobian J of the weighted
// residual r, per axis with its own variance and correlation inflation.
Eigen::MatrixXd parameter_covariance(const Layout& layout, const Eigen::MatrixXd& J,
                                     const Eigen::VectorXd& r);
// Final rss, n_eff, k, the parameters with their 95 % intervals and the
// parameters of different effects the data cannot separate.
void report_intervals(const FitContext& ctx, ModelFit& fit);

}  // namespace truecut::analysis::diagnosis
