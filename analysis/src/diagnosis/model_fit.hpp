// The explanation stage: candidate signatures of the named effects, sparse
// selection by BIC, and the nonlinear fit of the selected effects'
// parameters by re-simulation (Levenberg–Marquardt, numeric Jacobian).
#pragma once

#include <Eigen/Dense>
#include <functional>
#include <string>
#include <vector>

#include "trace.hpp"
#include "truecut/analysis/diagnosis/diagnosis.hpp"

namespace truecut::analysis::diagnosis {

// Which samples of which axes enter the fit, and their weights (1 / the
// axis' noise floor): residuals are stacked axis after axis.
struct Layout {
  std::vector<int> axes;
  std::vector<std::vector<std::size_t>> index;  // per axis, the samples used
  std::vector<double> weight;                   // per axis
  // Per axis, per sample used (parallel to index), a factor on `weight`:
  // 1 / √(1 + (u/σ)²) where the re-simulation itself is uncertain by u
  // (coarse samples); empty: 1 everywhere.
  std::vector<std::vector<double>> sample_weight;
  double w(std::size_t axis, std::size_t i) const {
    return weight[axis] * (sample_weight.empty() ? 1.0 : sample_weight[axis][i]);
  }
  std::size_t size() const;
  Eigen::VectorXd stack(const std::array<std::vector<double>, sim::kJointCount>& per_joint) const;
  // Profiles out each axis' constant offset (a nuisance): removes the
  // projection on the axis' weights (its weighted mean).
  void center(Eigen::Ref<Eigen::VectorXd> v) const;
  // Lag-1 autocorrelation within the axes.
  double lag1(const Eigen::VectorXd& v) const;
};

struct Candidate {
  std::string effect;
  int joint = -1;                 // -1: global (squareness)
  std::string axis;               // "x", or the plane "xy"
  std::string group;              // effect:axis[:part]; variants of a group exclude each other
  std::string variant;            // e.g. "tau_s=120" (empty when none)
  std::vector<std::string> keys;  // parameters the nonlinear fit moves
  double min_effect_ratio = 0.0;  // > 0: overrides FitContext::min_effect_ratio
  Eigen::MatrixXd X;              // weighted, centred signature columns
  // Puts the effect into `params` from the linear coefficients of X; false
  // when they have no physical meaning (e.g. a negative lag).
  std::function<bool(sim::MachineParams&, const Eigen::VectorXd&)> apply;
  std::string label() const { return group + (variant.empty() ? "" : " (" + variant + ")"); }
};

struct FitContext {
  const Trace* trace = nullptr;
  std::array<std::vector<double>, sim::kJointCount> aligned;  // recorded targets
  double delay_s = 0.0;  // the simulation is delayed by this to meet the recording
  Layout layout;
  double max_period_s = 1e-3;
  double bic_threshold = 10.0;
  double min_effect_ratio = 0.1;  // DiagnosisOptions::min_effect_ratio
  // The held-out samples (same weights and delay), or null: an effect must
  // lower their residual to be kept.
  const FitContext* heldout = nullptr;
  std::function<void(const std::string&)> progress;
  // Re-simulations of *trace kept for reuse (null: none kept).
  ResimCache* cache = nullptr;
};

// Re-simulation delayed by ctx.delay_s.
Simulated simulate_aligned(const FitContext& ctx, const sim::MachineParams& params);
// Its targets only (the motor positions not delayed).
std::array<std::vector<double>, sim::kJointCount> simulate_aligned_targets(
    const FitContext& ctx, const sim::MachineParams& params);
Eigen::VectorXd weighted_residual(const FitContext& ctx, const sim::MachineParams& params);

std::vector<Candidate> build_candidates(const FitContext& ctx, const sim::MachineParams& base);

struct SelectedEffect {
  std::string effect;
  int joint = -1;
  std::string axis, group, variant;
  std::vector<std::string> keys;
  double delta_bic = 0.0;
  double min_effect_ratio = 0.1;  // least contribution claimed, in units of the floor
};

struct ModelFit {
  sim::MachineParams params;
  std::vector<SelectedEffect> selected;
  std::vector<Parameter> parameters;  // parallel to the concatenated keys of `selected`
  std::vector<std::vector<Parameter>> per_effect;
  std::vector<NotIdentifiable> not_identifiable;
  std::vector<NotConfirmed> not_confirmed;
  std::vector<std::string> tested;
  double rss = 0.0;  // weighted, centred
  std::size_t n = 0;
  double n_eff = 0.0;
  int k = 0;  // free parameters
  double bic() const;
};

// `params` with one effect's keys back to their values in `reference` (or
// the effect off when `reference` does not have it).
sim::MachineParams without_effect(const sim::MachineParams& params,
                                  const sim::MachineParams& reference,
                                  const SelectedEffect& effect);

// Rounds of (signatures → forward selection → nonlinear fit) from `base`
// until nothing more is selected.
ModelFit fit_model(const FitContext& ctx, const sim::MachineParams& base);

}  // namespace truecut::analysis::diagnosis
