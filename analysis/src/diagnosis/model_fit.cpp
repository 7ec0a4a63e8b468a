#include "model_fit.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <set>

#include "effect_params.hpp"
#include "truecut/rt/number_format.hpp"

namespace truecut::analysis::diagnosis {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// The residual sum of squares of `r` after least squares on the columns of X.
double rss_after(const MatrixXd& X, const VectorXd& r, VectorXd* coef = nullptr) {
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

struct Key {
  std::string effect;
  int joint;
  std::string key;
};

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

}  // namespace

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
  Simulated sim = resimulate(params, *ctx.trace, ctx.max_period_s);
  delay_simulated(ctx.trace->t_s, sim, ctx.delay_s);
  return sim;
}

VectorXd weighted_residual(const FitContext& ctx, const sim::MachineParams& params) {
  const Simulated sim = simulate_aligned(ctx, params);
  VectorXd r = ctx.layout.stack(ctx.aligned) - ctx.layout.stack(sim.target);
  ctx.layout.center(r);
  return r;
}

namespace {

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

// A candidate of one parameter that must stay positive (a play, a friction):
// applied by adding its linear coefficient to the believed value.
Candidate single_positive(const std::string& effect, int joint, const std::string& axis,
                          const std::string& key) {
  Candidate c;
  c.effect = effect;
  c.joint = joint;
  c.axis = axis;
  c.group = effect + ":" + axis;
  c.keys = {key};
  c.apply = [effect, joint, key](sim::MachineParams& p, const VectorXd& coef) {
    enable_effect(p, effect, joint);
    double* v = param_ptr(p, effect, joint, key);
    if (!v || !(*v + coef[0] > 0)) return false;
    *v += coef[0];
    return true;
  };
  return c;
}

}  // namespace

std::vector<Candidate> build_candidates(const FitContext& ctx, const sim::MachineParams& base) {
  const Trace& tr = *ctx.trace;
  const Layout& L = ctx.layout;
  const Simulated sim0 = simulate_aligned(ctx, base);
  const VectorXd s0 = L.stack(sim0.target);
  std::vector<Candidate> out;

  auto column = [&](int joint, const std::vector<double>& values) {
    std::array<std::vector<double>, sim::kJointCount> v;
    v[joint] = values;
    VectorXd c = L.stack(v);
    L.center(c);
    return c;
  };
  // Sensitivity of the simulated targets to one parameter, by re-simulation.
  auto fd_column = [&](const sim::MachineParams& p0, const std::string& effect, int joint,
                       const std::string& key, double h) {
    sim::MachineParams p = p0;
    enable_effect(p, effect, joint);
    *param_ptr(p, effect, joint, key) += h;
    VectorXd c = (L.stack(simulate_aligned(ctx, p).target) - s0) / h;
    L.center(c);
    return c;
  };
  const double t0 = tr.t_s.front(), span_t = tr.t_s.back() - tr.t_s.front();
  const double sample_period_s = median_period(tr.t_s);

  for (int j : L.axes) {
    const std::string ax(sim::kJointNames[j]);
    const bool dynamic = base.effects.servo_lag.active(j) != nullptr;
    // Sampled slower than the believed loop's time constant 1/Kv: the loop's
    // transients (and a friction spike, which decays with them) fall between
    // the samples, where the command itself is only interpolated; an
    // adjustment must then move the residual by at least the noise floor.
    const bool loop_unresolved =
        dynamic && sample_period_s > 1.0 / base.effects.servo_lag.active(j)->kv_per_s;
    const auto v_cmd = derivative(tr.t_s, tr.cmd[j]);
    double travel = 0, v_max = 0;
    {
      const auto [lo, hi] = std::minmax_element(tr.cmd[j].begin(), tr.cmd[j].end());
      travel = *hi - *lo;
      for (double v : v_cmd)
        v_max = std::max(v_max, std::abs(v));
    }
    if (v_max <= 0) continue;  // the joint never moves: nothing to tell apart

    // servo_lag
    {
      Candidate c;
      c.effect = "servo_lag";
      c.joint = j;
      c.axis = ax;
      c.group = "servo_lag:" + ax;
      c.keys = {"kv_per_s", "ff1"};
      if (!dynamic) {
        std::vector<double> neg_v(v_cmd.size());
        for (std::size_t k = 0; k < v_cmd.size(); ++k)
          neg_v[k] = -v_cmd[k];
        c.X = column(j, neg_v);
        c.apply = [j](sim::MachineParams& p, const VectorXd& coef) {
          const double lag_s = coef[0];  // (1 − ff1) / Kv
          if (!(lag_s > 1e-4)) return false;
          enable_effect(p, "servo_lag", j);
          p.effects.servo_lag.axes[j] =
              sim::ServoLagAxis{clamp_param("kv_per_s", 1.0 / lag_s), 0.0};
          return true;
        };
      } else {
        const auto& sl = *base.effects.servo_lag.axes[j];
        c.X.resize(s0.size(), 2);
        c.X.col(0) =
            fd_column(base, "servo_lag", j, "kv_per_s", param_step("kv_per_s", sl.kv_per_s));
        c.X.col(1) = fd_column(base, "servo_lag", j, "ff1", sl.ff1 > 1.4 ? -1e-3 : 1e-3);
        c.apply = [j](sim::MachineParams& p, const VectorXd& coef) {
          auto& a = *p.effects.servo_lag.axes[j];
          a.kv_per_s = clamp_param("kv_per_s", a.kv_per_s + coef[0]);
          a.ff1 = clamp_param("ff1", a.ff1 + coef[1]);
          return true;
        };
        c.min_effect_ratio = loop_unresolved ? 1.0 : 0.0;
      }
      out.push_back(std::move(c));
    }
    // reversal_spike: friction acts through the servo, so only on a dynamic joint.
    if (dynamic) {
      Candidate c = single_positive("reversal_spike", j, ax, coulomb_key(j));
      const double inertia = base.joints[j].drive.inertia;
      const double h = sim::joint_kind(j) == sim::JointKind::Linear
                           ? 0.05 * inertia
                           : 50.0 * inertia * std::numbers::pi / 180;
      c.X = fd_column(base, "reversal_spike", j, coulomb_key(j), std::max(h, 0.5));
      c.min_effect_ratio = loop_unresolved ? 1.0 : 0.0;
      out.push_back(std::move(c));
    }
    if (!tr.meas[j]) continue;  // the encoder sees only the servo effects

    {
      Candidate c = single_positive("backlash", j, ax, play_key(j));
      c.X = fd_column(base, "backlash", j, play_key(j), 1e-3);
      out.push_back(std::move(c));
    }
    if (j >= 3) continue;
    const auto* pitch = base.effects.pitch_error.active(j);
    const auto& motor = sim0.motor[j];
    {
      Candidate c;
      c.effect = "pitch_error";
      c.joint = j;
      c.axis = ax;
      c.group = "pitch_error:" + ax + ":scale";
      c.keys = {"scale_um_per_m"};
      const double ref = pitch ? pitch->reference_mm : 0.0;
      std::vector<double> col(motor.size());
      for (std::size_t k = 0; k < motor.size(); ++k)
        col[k] = (motor[k] - ref) * 1e-6;
      c.X = column(j, col);
      c.apply = [j](sim::MachineParams& p, const VectorXd& coef) {
        enable_effect(p, "pitch_error", j);
        p.effects.pitch_error.axes[j]->scale_um_per_m += coef[0];
        return true;
      };
      out.push_back(std::move(c));
    }
    {
      std::vector<double> periods;
      if (pitch && pitch->periodic_amplitude_um > 0) {
        periods.push_back(pitch->periodic_period_mm);
      } else {
        for (double p = 1.0; p <= 200.0; p *= 1.05)
          if (p <= travel / 2) periods.push_back(std::round(p * 1000) / 1000);
      }
      for (double P : periods) {
        Candidate c;
        c.effect = "pitch_error";
        c.joint = j;
        c.axis = ax;
        c.group = "pitch_error:" + ax + ":periodic";
        c.variant = "periodic_period_mm=" + rt::format_printf("%.4g", P);
        c.keys = {"periodic_amplitude_um", "periodic_phase_deg", "periodic_period_mm"};
        std::vector<double> sn(motor.size()), cs(motor.size());
        for (std::size_t k = 0; k < motor.size(); ++k) {
          const double ph = 2 * std::numbers::pi * motor[k] / P;
          sn[k] = std::sin(ph) * 1e-3;
          cs[k] = std::cos(ph) * 1e-3;
        }
        c.X.resize(s0.size(), 2);
        c.X.col(0) = column(j, sn);
        c.X.col(1) = column(j, cs);
        c.apply = [j, P](sim::MachineParams& p, const VectorXd& coef) {
          enable_effect(p, "pitch_error", j);
          auto& e = *p.effects.pitch_error.axes[j];
          const double phi = e.periodic_phase_deg * std::numbers::pi / 180;
          const double as = e.periodic_amplitude_um * std::cos(phi) + coef[0];
          const double ac = e.periodic_amplitude_um * std::sin(phi) + coef[1];
          e.periodic_period_mm = P;
          e.periodic_amplitude_um = std::hypot(as, ac);
          e.periodic_phase_deg = std::atan2(ac, as) * 180 / std::numbers::pi;
          return e.periodic_amplitude_um > 0;
        };
        out.push_back(std::move(c));
      }
    }
    if (!base.effects.thermal_drift.active(j) && span_t > 0) {
      for (double f : {0.03, 0.1, 0.3, 1.0, 3.0}) {
        const double tau = std::round(span_t * f * 1000) / 1000;
        if (!(tau > 0)) continue;
        Candidate c;
        c.effect = "thermal_drift";
        c.joint = j;
        c.axis = ax;
        c.group = "thermal_drift:" + ax;
        c.variant = "tau_s=" + rt::format_printf("%.4g", tau);
        c.keys = {"gain_mm", "tau_s"};
        std::vector<double> col(tr.rows());
        for (std::size_t k = 0; k < col.size(); ++k)
          col[k] = -std::expm1(-(tr.t_s[k] - t0) / tau);
        c.X = column(j, col);
        c.apply = [j, tau](sim::MachineParams& p, const VectorXd& coef) {
          enable_effect(p, "thermal_drift", j);
          auto& e = *p.effects.thermal_drift.axes[j];
          e.gain_mm = coef[0];
          e.tau_s = tau;
          e.driver = sim::ThermalDriver::Time;
          return true;
        };
        out.push_back(std::move(c));
      }
      // Driven by the spindle power (u = P / P_ref, P_ref 10 kW): the
      // first-order response to the recorded power, integrated exactly.
      const auto& pw = tr.spindle_power_kw;
      const bool powered =
          !pw.empty() && std::any_of(pw.begin(), pw.end(), [](double v) { return v > 0; });
      for (double f : {0.03, 0.1, 0.3, 1.0, 3.0}) {
        const double tau = std::round(span_t * f * 1000) / 1000;
        if (!powered || !(tau > 0)) continue;
        constexpr double kRefKw = 10.0;
        Candidate c;
        c.effect = "thermal_drift";
        c.joint = j;
        c.axis = ax;
        c.group = "thermal_drift:" + ax;
        c.variant = "driver=spindle_power tau_s=" + rt::format_printf("%.4g", tau);
        c.keys = {"gain_mm", "tau_s"};
        std::vector<double> col(tr.rows(), 0.0);
        for (std::size_t k = 1; k < col.size(); ++k)
          col[k] = col[k - 1] + (pw[k - 1] / kRefKw - col[k - 1]) *
                                    -std::expm1(-(tr.t_s[k] - tr.t_s[k - 1]) / tau);
        c.X = column(j, col);
        c.apply = [j, tau](sim::MachineParams& p, const VectorXd& coef) {
          enable_effect(p, "thermal_drift", j);
          auto& e = *p.effects.thermal_drift.axes[j];
          e.gain_mm = coef[0];
          e.tau_s = tau;
          e.driver = sim::ThermalDriver::SpindlePower;
          e.reference_power_kw = kRefKw;
          return true;
        };
        out.push_back(std::move(c));
      }
    }
  }
  // straightness: the bow of a moving axis' path seen in another axis: its
  // quadratic term and where the bow is flat (reference_mm; a description's
  // reference need not be the middle of the travel recorded, and a
  // quadratic about the wrong point carries a slope that nothing else in
  // the model takes up). Linear selection on s² and s about the believed
  // (or middle-of-travel) reference: q(s − δ)² = q s² − 2qδ s + const. The
  // cubic term is held at its believed value (over a few hundred mm it is
  // nearly collinear with the quadratic one); a component with a cubic term
  // keeps its reference.
  for (int i = 0; i < sim::kStraightnessCount; ++i) {
    const int moving = sim::kStraightnessMoving[i], dir = sim::kStraightnessDirection[i];
    const bool has_target =
        std::find(L.axes.begin(), L.axes.end(), dir) != L.axes.end() && tr.meas[dir];
    if (!has_target || tr.cmd[moving].empty()) continue;
    const auto [lo, hi] = std::minmax_element(tr.cmd[moving].begin(), tr.cmd[moving].end());
    const double span = *hi - *lo;
    if (span <= 1.0) continue;
    const auto* believed = base.effects.straightness.active()
                               ? &base.effects.straightness.params.components[i]
                               : nullptr;
    const bool has = believed && *believed;
    const double ref = has ? (*believed)->reference_mm : std::round((*lo + *hi) / 2 * 1000) / 1000;
    const bool move_ref = !has || (*believed)->cubic_um_per_m3 == 0.0;
    const std::string name = sim::kStraightnessNames[i];
    Candidate c;
    c.effect = "straightness";
    c.axis = name;
    c.group = "straightness:" + name;
    c.keys = {name + ".quadratic_um_per_m2"};
    if (move_ref) c.keys.push_back(name + ".reference_mm");
    const auto& pos = sim0.motor[moving].empty() ? tr.cmd[moving] : sim0.motor[moving];
    std::vector<double> sq(tr.rows()), sl(tr.rows());
    for (std::size_t k = 0; k < sq.size(); ++k) {
      const double sm = (pos[k] - ref) * 1e-3;  // m
      sq[k] = sm * sm * 1e-3;                   // mm per µm/m²
      sl[k] = sm * 1e-3;                        // mm per µm/m
    }
    c.X.resize(s0.size(), move_ref ? 2 : 1);
    c.X.col(0) = column(dir, sq);
    if (move_ref) c.X.col(1) = column(dir, sl);
    const double lo_ok = *lo - span, hi_ok = *hi + span;
    c.apply = [i, ref, move_ref, lo_ok, hi_ok](sim::MachineParams& p, const VectorXd& coef) {
      p.effects.straightness.enabled = true;
      auto& comp = p.effects.straightness.params.components[i];
      if (!comp) comp = sim::StraightnessComponent{0.0, 0.0, ref};
      comp->quadratic_um_per_m2 += coef[0];
      if (!move_ref) return true;
      const double q = comp->quadratic_um_per_m2;
      if (q == 0.0) return false;
      // q s² + b s = q (s + b/(2q))² − …: the bow is flat at s = −b/(2q).
      comp->reference_mm = ref - coef[1] / (2 * q) * 1e3;
      // A flat point far outside the travel is a slope, not a bow.
      return comp->reference_mm >= lo_ok && comp->reference_mm <= hi_ok;
    };
    out.push_back(std::move(c));
  }
  // squareness: the error of one axis grows with the position of another.
  const struct {
    const char* key;
    int target, other;
  } planes[] = {
      {"xy_urad", sim::kX, sim::kY}, {"yz_urad", sim::kY, sim::kZ}, {"zx_urad", sim::kX, sim::kZ}};
  for (const auto& pl : planes) {
    const bool has_target =
        std::find(L.axes.begin(), L.axes.end(), pl.target) != L.axes.end() && tr.meas[pl.target];
    if (!has_target || tr.cmd[pl.other].empty()) continue;
    const auto [lo, hi] = std::minmax_element(tr.cmd[pl.other].begin(), tr.cmd[pl.other].end());
    if (*hi - *lo <= 1e-6) continue;
    Candidate c;
    c.effect = "squareness";
    c.axis = std::string(pl.key).substr(0, 2);
    c.group = "squareness:" + c.axis;
    c.keys = {pl.key};
    std::vector<double> col(tr.rows());
    const auto& pos = sim0.motor[pl.other].empty() ? tr.cmd[pl.other] : sim0.motor[pl.other];
    for (std::size_t k = 0; k < col.size(); ++k)
      col[k] = pos[k] * 1e-6;
    c.X = column(pl.target, col);
    const std::string key = pl.key;
    c.apply = [key](sim::MachineParams& p, const VectorXd& coef) {
      enable_effect(p, "squareness", -1);
      *param_ptr(p, "squareness", -1, key) += coef[0];
      return true;
    };
    out.push_back(std::move(c));
  }
  return out;
}

namespace {

struct Selection {
  std::vector<const Candidate*> chosen;
  std::vector<double> delta_bic;
  VectorXd coef;  // joint fit, columns in the order of chosen
  std::vector<NotIdentifiable> confusions;
};

// Forward selection over the groups by BIC; among a group's variants the best one.
// The RMS of a stacked vector over the axes it touches (those with at
// least 1 % of the largest axis' RMS).
double rms_on_support(const VectorXd& v, const Layout& layout) {
  std::vector<double> ms;
  Eigen::Index r = 0;
  for (const auto& ix : layout.index) {
    const Eigen::Index m = Eigen::Index(ix.size());
    ms.push_back(m ? v.segment(r, m).squaredNorm() / double(m) : 0.0);
    r += m;
  }
  const double top = ms.empty() ? 0.0 : *std::max_element(ms.begin(), ms.end());
  double ss = 0, n = 0;
  for (std::size_t a = 0; a < ms.size(); ++a)
    if (ms[a] > 0 && ms[a] >= 1e-4 * top) {
      const double m = double(layout.index[a].size());
      ss += ms[a] * m, n += m;
    }
  return n > 0 ? std::sqrt(ss / n) : 0.0;
}

Selection forward_select(const std::vector<Candidate>& cands, const VectorXd& r, double threshold,
                         double min_effect, const Layout& layout, const sim::MachineParams& base,
                         double& n_eff_out) {
  const Eigen::Index n = r.size();
  std::map<std::string, std::vector<const Candidate*>> groups;
  for (const auto& c : cands)
    groups[c.group].push_back(&c);
  // Noise correlation from the fit with every group's best single variant.
  std::vector<const Candidate*> best_of;
  for (const auto& [g, vs] : groups) {
    const Candidate* best = nullptr;
    double best_rss = INFINITY;
    for (const auto* v : vs) {
      const double rss = rss_after(v->X, r);
      if (rss < best_rss) best_rss = rss, best = v;
    }
    best_of.push_back(best);
  }
  std::vector<const MatrixXd*> all;
  for (const auto* c : best_of)
    all.push_back(&c->X);
  VectorXd coef_all;
  const MatrixXd X_all = hcat(all, n);
  rss_after(X_all, r, &coef_all);
  const VectorXd res_all = X_all.cols() ? VectorXd(r - X_all * coef_all) : r;
  double rho = 0, den = res_all.squaredNorm();
  for (Eigen::Index i = 1; i < n; ++i)
    rho += res_all[i] * res_all[i - 1];
  rho = den > 0 ? rho / den : 0;
  const double n_eff = n_eff_of(double(n), rho);
  n_eff_out = n_eff;

  Selection sel;
  std::set<std::string> used, rejected;
  double rss = r.squaredNorm();
  for (;;) {
    const Candidate* best = nullptr;
    double best_dbic = -threshold, best_rss = rss;
    std::vector<const MatrixXd*> cur;
    for (const auto* c : sel.chosen)
      cur.push_back(&c->X);
    for (const auto& [g, vs] : groups) {
      if (used.count(g) || rejected.count(g)) continue;
      for (const auto* v : vs) {
        auto parts = cur;
        parts.push_back(&v->X);
        const double rss_new = rss_after(hcat(parts, n), r);
        const double dbic = n_eff * std::log(std::max(rss_new, 1e-300) / rss) +
                            double(v->X.cols()) * std::log(n_eff);
        if (dbic < best_dbic) best_dbic = dbic, best = v, best_rss = rss_new;
      }
    }
    if (!best) break;
    auto parts = cur;
    parts.push_back(&best->X);
    VectorXd coef;
    rss_after(hcat(parts, n), r, &coef);
    // Check that every chosen effect still has a physical meaning.
    sim::MachineParams trial = base;
    bool ok = true;
    Eigen::Index c0 = 0;
    std::vector<const Candidate*> next = sel.chosen;
    next.push_back(best);
    for (const auto* c : next) {
      ok = ok && c->apply(trial, coef.segment(c0, c->X.cols()));
      c0 += c->X.cols();
    }
    // Too small to be physics rather than a departure of the noise from the
    // white Gaussian noise the BIC assumes (weighted units: the floor is 1).
    const VectorXd contrib = best->X * coef.tail(best->X.cols());
    const double least = best->min_effect_ratio > 0 ? best->min_effect_ratio : min_effect;
    if (!ok || rms_on_support(contrib, layout) < least) {
      rejected.insert(best->group);
      continue;
    }
    sel.chosen = next;
    sel.delta_bic.push_back(best_dbic);
    sel.coef = coef;
    used.insert(best->group);
    rss = best_rss;
  }

  // Not identifiable: a chosen group that another group replaces almost as well.
  std::vector<const MatrixXd*> cur;
  for (const auto* c : sel.chosen)
    cur.push_back(&c->X);
  Eigen::Index c0 = 0;
  for (std::size_t i = 0; i < sel.chosen.size(); ++i) {
    const Candidate* s = sel.chosen[i];
    const VectorXd contrib = s->X * sel.coef.segment(c0, s->X.cols());
    c0 += s->X.cols();
    for (const auto* o : best_of) {
      if (o->group == s->group || used.count(o->group)) continue;
      // The other group's best variant for this contribution.
      const Candidate* ob = nullptr;
      double ob_rss = INFINITY;
      for (const auto* v : groups[o->group]) {
        auto parts = cur;
        parts[i] = &v->X;
        const double rr = rss_after(hcat(parts, n), r);
        if (rr < ob_rss) ob_rss = rr, ob = v;
      }
      const double d = n_eff * std::log(std::max(ob_rss, 1e-300) / std::max(rss, 1e-300)) +
                       double(ob->X.cols() - s->X.cols()) * std::log(n_eff);
      if (d >= threshold) continue;
      const double resid = rss_after(ob->X, contrib);
      const double corr = contrib.squaredNorm() > 0
                              ? std::sqrt(std::max(0.0, 1 - resid / contrib.squaredNorm()))
                              : 0;
      NotIdentifiable ni;
      ni.first = s->group;
      ni.second = ob->group;
      ni.correlation = corr;
      ni.separate_by = separation_hint(s->effect, ob->effect);
      sel.confusions.push_back(ni);
    }
  }
  return sel;
}

}  // namespace

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

}  // namespace

ModelFit fit_model(const FitContext& ctx, const sim::MachineParams& base) {
  ModelFit fit;
  fit.params = base;
  fit.n = ctx.layout.size();
  std::set<std::string> have;
  auto say = [&](const std::string& s) {
    if (ctx.progress) ctx.progress(s);
  };
  for (int round = 0; round < 3; ++round) {
    const VectorXd r = weighted_residual(ctx, fit.params);
    auto cands = build_candidates(ctx, fit.params);
    std::vector<Candidate> open;
    for (auto& c : cands) {
      if (have.count(c.group)) continue;
      const std::string name = c.effect + (c.axis.empty() ? "" : ":" + c.axis);
      if (std::find(fit.tested.begin(), fit.tested.end(), name) == fit.tested.end())
        fit.tested.push_back(name);
      open.push_back(std::move(c));
    }
    double n_eff = 0;
    const Selection sel = forward_select(open, r, ctx.bic_threshold, ctx.min_effect_ratio,
                                         ctx.layout, fit.params, n_eff);
    for (const auto& ni : sel.confusions) {
      bool dup = false;
      for (const auto& e : fit.not_identifiable)
        dup = dup || (e.first == ni.first && e.second == ni.second);
      if (!dup) fit.not_identifiable.push_back(ni);
    }
    if (sel.chosen.empty()) break;
    const ModelFit before_round = fit;
    const double rss_before_round = r.squaredNorm();
    Eigen::Index c0 = 0;
    for (std::size_t i = 0; i < sel.chosen.size(); ++i) {
      const Candidate* c = sel.chosen[i];
      c->apply(fit.params, sel.coef.segment(c0, c->X.cols()));
      c0 += c->X.cols();
      fit.selected.push_back(
          {c->effect, c->joint, c->axis, c->group, c->variant, c->keys, sel.delta_bic[i],
           c->min_effect_ratio > 0 ? c->min_effect_ratio : ctx.min_effect_ratio});
      have.insert(c->group);
      say("selected " + c->label() + " (ΔBIC " + rt::format_printf("%.4g", sel.delta_bic[i]) + ")");
    }
    normalise_periodic(fit.params);
    // A servo loop new to the model: the linear signature gives only the
    // steady lag (1 − ff1)/Kv; the start pair is chosen by re-simulation.
    for (const auto* c : sel.chosen) {
      if (c->effect != "servo_lag" || before_round.params.effects.servo_lag.active(c->joint))
        continue;
      auto& a = *fit.params.effects.servo_lag.axes[c->joint];
      const double lag_s = (1.0 - a.ff1) / a.kv_per_s;
      sim::ServoLagAxis best = a;
      double best_rss = weighted_residual(ctx, fit.params).squaredNorm();
      for (double ff1 : {0.0, 0.5, 0.8, 0.9, 0.95, 0.98, 0.99}) {
        sim::MachineParams p = fit.params;
        auto& b = *p.effects.servo_lag.axes[c->joint];
        b.ff1 = ff1;
        b.kv_per_s = clamp_param("kv_per_s", (1.0 - ff1) / lag_s);
        const double rr = weighted_residual(ctx, p).squaredNorm();
        if (rr < best_rss) best_rss = rr, best = b;
      }
      a = best;
    }

    // Nonlinear fit of every selected parameter by re-simulation.
    refine(ctx, fit);
    const Eigen::Index m = Eigen::Index(keys_of(fit.selected).size());
    // Verified by re-simulation: the round's effects must pay for their
    // parameters in the real model too, not only in the linearisation.
    const int added = int(m) - int(keys_of(before_round.selected).size());
    const double gain =
        n_eff * std::log(std::max(fit.rss, 1e-300) / rss_before_round) + added * std::log(n_eff);
    say("fitted " + std::to_string(m) + " parameters by re-simulation, round " +
        std::to_string(round + 1) + " (ΔBIC " + rt::format_printf("%.4g", gain) + ")");
    // Backward elimination: an effect selected on the linearisation that the
    // re-simulated model does not need any more (it stood in for a
    // linearisation error of another one) is dropped.
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
      say("dropped " + fit.selected[weakest].group + " (re-simulated ΔBIC " +
          rt::format_printf("%.4g", -weakest_cost) + ")");
      fit.params = without_effect(fit.params, base, fit.selected[weakest]);
      have.erase(fit.selected[weakest].group);
      fit.selected.erase(fit.selected.begin() + std::ptrdiff_t(weakest));
      // The others were fitted beside it: fit them again without it.
      refine(ctx, fit);
    }
    if (gain > -ctx.bic_threshold || fit.selected.empty()) {
      say("re-simulation does not confirm the round's effects; dropped");
      auto tested = fit.tested;
      auto confusions = fit.not_identifiable;
      fit = before_round;
      fit.tested = tested;
      fit.not_identifiable = confusions;
      break;
    }
  }

  // An adjustment of an effect the believed model already has is kept only
  // when the data move it: when the 95 % interval of every one of its
  // parameters still covers the believed value, the believed value stands.
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
      say("dropped " + sel.group + ": the believed value lies inside the fitted interval");
      fit.params = without_effect(fit.params, base, sel);
      fit.selected.erase(fit.selected.begin() + std::ptrdiff_t(e));
      refine(ctx, fit);
      dropped = true;
    }
  }

  // Too small to matter, re-simulated: an effect (or an adjustment of a
  // believed one) whose contribution stays below min_effect_ratio of the
  // noise floor is not claimed, however strongly the BIC favours it (with
  // noise-free or quantised data the BIC sees any systematic misfit).
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
    say("dropped " + fit.selected[smallest].group + ": its contribution is " +
        rt::format_printf("%.4g", smallest_rms) + " of the noise floor");
    fit.params = without_effect(fit.params, base, fit.selected[smallest]);
    fit.selected.erase(fit.selected.begin() + std::ptrdiff_t(smallest));
    refine(ctx, fit);
    dropped = true;
  }

  // Proven on data it was not fitted on: an effect that raises the held-out
  // residual (the fitted model against the same model without it; the
  // offsets those of the fitted block, as a prediction must carry them) is
  // not confirmed and left out; the others are fitted again without it.
  if (ctx.heldout) {
    // Weighted held-out RSS and the sample count.
    auto heldout_rss = [&](const sim::MachineParams& p) {
      const Simulated st = simulate_aligned(ctx, p);
      const Simulated sh = ctx.heldout->trace == ctx.trace ? st : simulate_aligned(*ctx.heldout, p);
      const Layout& tl = ctx.layout;
      const Layout& hl = ctx.heldout->layout;
      double rss = 0;
      for (std::size_t a = 0; a < tl.axes.size(); ++a) {
        const int j = tl.axes[a];
        double off = 0, uu = 0;
        for (std::size_t i = 0; i < tl.index[a].size(); ++i) {
          const std::size_t k = tl.index[a][i];
          const double u2 = tl.w(a, i) * tl.w(a, i);
          off += u2 * (ctx.aligned[j][k] - st.target[j][k]), uu += u2;
        }
        off = uu > 0 ? off / uu : 0.0;
        for (std::size_t i = 0; i < hl.index[a].size(); ++i) {
          const std::size_t k = hl.index[a][i];
          const double r = (ctx.heldout->aligned[j][k] - sh.target[j][k] - off) * hl.w(a, i);
          rss += r * r;
        }
      }
      return rss;
    };
    // An RMS in mm for the report: the weighted RSS over the sum of squared weights.
    auto rms_mm = [&](double rss) {
      const Layout& hl = ctx.heldout->layout;
      double ww = 0;
      for (std::size_t a = 0; a < hl.index.size(); ++a)
        for (std::size_t i = 0; i < hl.index[a].size(); ++i)
          ww += hl.w(a, i) * hl.w(a, i);
      return ww > 0 ? std::sqrt(rss / ww) : 0.0;
    };
    const double none = heldout_rss(base);
    for (bool dropped = true; dropped && !fit.selected.empty();) {
      dropped = false;
      const double with = heldout_rss(fit.params);
      std::size_t worst = 0;
      double worst_gain = INFINITY, worst_without = 0;
      for (std::size_t e = 0; e < fit.selected.size(); ++e) {
        const double without = heldout_rss(without_effect(fit.params, base, fit.selected[e]));
        if (without - with < worst_gain)
          worst_gain = without - with, worst = e, worst_without = without;
      }
      // About zero: the held-out data do not see the effect (e.g. no
      // reversal of that axis there); they neither confirm nor refute it.
      // Effects that help each other to a worse prediction than the
      // believed model are dropped too, the least useful first.
      if (worst_gain >= -1e-9 * with && with <= none * (1 + 1e-9)) break;
      const auto& sel = fit.selected[worst];
      say("dropped " + sel.group + ": the held-out residual does not confirm it");
      fit.not_confirmed.push_back({sel.effect, sel.axis, rms_mm(with), rms_mm(worst_without)});
      fit.params = without_effect(fit.params, base, sel);
      fit.selected.erase(fit.selected.begin() + std::ptrdiff_t(worst));
      refine(ctx, fit);
      dropped = true;
    }
  }

  // Confusions found on the linearisation count only for effects that stayed.
  std::erase_if(fit.not_identifiable, [&](const NotIdentifiable& ni) {
    return std::none_of(fit.selected.begin(), fit.selected.end(),
                        [&](const SelectedEffect& s) { return s.group == ni.first; });
  });

  // Confidence intervals from the Jacobian at the solution, inflated for
  // correlated residuals (effective sample count).
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
    const MatrixXd J = jacobian(ctx, fit.params, keys, th, r0);
    cov = parameter_covariance(ctx.layout, J, r0);
  }
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
  // Parameters of different effects the data cannot separate.
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
  return fit;
}

}  // namespace truecut::analysis::diagnosis
