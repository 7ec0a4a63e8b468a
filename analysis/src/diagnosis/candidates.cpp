// The candidates of the explanation stage: each named effect's signature,
// the change of the weighted, centred residual per unit of its parameters,
// linearised around the current model (analytic where the effect is linear
// in its parameters, else by re-simulation).
#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "effect_params.hpp"
#include "fit_steps.hpp"

namespace truecut::analysis::diagnosis {

namespace {

using Eigen::VectorXd;

// What every signature is built from: the recording, the layout and the
// current model's re-simulation.
struct SignatureBasis {
  const FitContext& ctx;
  const Trace& tr;
  const Layout& L;
  const sim::MachineParams& base;
  Simulated sim0;
  VectorXd s0;

  SignatureBasis(const FitContext& c, const sim::MachineParams& b)
      : ctx(c),
        tr(*c.trace),
        L(c.layout),
        base(b),
        sim0(simulate_aligned(c, b)),
        s0(L.stack(sim0.target)) {}

  // A column of one joint's values, weighted and centred.
  VectorXd column(int joint, const std::vector<double>& values) const {
    std::array<std::vector<double>, sim::kJointCount> v;
    v[joint] = values;
    VectorXd c = L.stack(v);
    L.center(c);
    return c;
  }
  // Sensitivity of the simulated targets to one parameter, by re-simulation.
  VectorXd fd_column(const sim::MachineParams& p0, const std::string& effect, int joint,
                     const std::string& key, double h) const {
    sim::MachineParams p = p0;
    enable_effect(p, effect, joint);
    *param_ptr(p, effect, joint, key) += h;
    VectorXd c = (L.stack(simulate_aligned_targets(ctx, p)) - s0) / h;
    L.center(c);
    return c;
  }
};

// One joint's command, as the candidates of that joint need it.
struct JointMotion {
  int j = 0;
  std::string ax;
  bool dynamic = false;          // the model has a servo loop on the joint
  bool loop_unresolved = false;  // sampled slower than the loop's time constant 1/Kv
  std::vector<double> v_cmd;
  double travel = 0, v_max = 0;
};

JointMotion joint_motion(const SignatureBasis& S, int j, double sample_period_s) {
  JointMotion m;
  m.j = j;
  m.ax = std::string(sim::kJointNames[j]);
  m.dynamic = S.base.effects.servo_lag.active(j) != nullptr;
  // Sampled slower than the believed loop's time constant 1/Kv: the loop's
  // transients (and a friction spike, which decays with them) fall between
  // the samples, where the command itself is only interpolated; an
  // adjustment must then move the residual by at least the noise floor.
  m.loop_unresolved =
      m.dynamic && sample_period_s > 1.0 / S.base.effects.servo_lag.active(j)->kv_per_s;
  m.v_cmd = derivative(S.tr.t_s, S.tr.cmd[j]);
  const auto [lo, hi] = std::minmax_element(S.tr.cmd[j].begin(), S.tr.cmd[j].end());
  m.travel = *hi - *lo;
  for (double v : m.v_cmd)
    m.v_max = std::max(m.v_max, std::abs(v));
  return m;
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

Candidate servo_lag_candidate(const SignatureBasis& S, const JointMotion& m) {
  const int j = m.j;
  const auto& base = S.base;
  Candidate c;
  c.effect = "servo_lag";
  c.joint = j;
  c.axis = m.ax;
  c.group = "servo_lag:" + m.ax;
  c.keys = {"kv_per_s", "ff1"};
  if (!m.dynamic) {
    std::vector<double> neg_v(m.v_cmd.size());
    for (std::size_t k = 0; k < m.v_cmd.size(); ++k)
      neg_v[k] = -m.v_cmd[k];
    c.X = S.column(j, neg_v);
    c.apply = [j](sim::MachineParams& p, const VectorXd& coef) {
      const double lag_s = coef[0];  // (1 − ff1) / Kv
      if (!(lag_s > 1e-4)) return false;
      enable_effect(p, "servo_lag", j);
      // The pair carries the lag: Kv = 1/lag with ff1 0 where Kv stays
      // within its range, else the largest Kv with the feed-forward that
      // gives the lag (a lag of 0.3 ms, Kv 100 with ff1 0.97, was put in as
      // Kv 1000 clamped, a lag of 1 ms, and the split scanned along that).
      const double kv = clamp_param("kv_per_s", 1.0 / lag_s);
      p.effects.servo_lag.axes[j] = sim::ServoLagAxis{kv, clamp_param("ff1", 1.0 - kv * lag_s)};
      return true;
    };
  } else {
    const auto& sl = *base.effects.servo_lag.axes[j];
    c.X.resize(S.s0.size(), 2);
    c.X.col(0) = S.fd_column(base, "servo_lag", j, "kv_per_s", param_step("kv_per_s", sl.kv_per_s));
    c.X.col(1) = S.fd_column(base, "servo_lag", j, "ff1", sl.ff1 > 1.4 ? -1e-3 : 1e-3);
    c.apply = [j](sim::MachineParams& p, const VectorXd& coef) {
      auto& a = *p.effects.servo_lag.axes[j];
      a.kv_per_s = clamp_param("kv_per_s", a.kv_per_s + coef[0]);
      a.ff1 = clamp_param("ff1", a.ff1 + coef[1]);
      return true;
    };
    c.min_effect_ratio = m.loop_unresolved ? 1.0 : 0.0;
  }
  return c;
}

// Friction acts through the servo: only on a dynamic joint.
Candidate reversal_spike_candidate(const SignatureBasis& S, const JointMotion& m) {
  const int j = m.j;
  Candidate c = single_positive("reversal_spike", j, m.ax, coulomb_key(j));
  const double inertia = S.base.joints[j].drive.inertia;
  const double h = sim::joint_kind(j) == sim::JointKind::kLinear
                       ? 0.05 * inertia
                       : 50.0 * inertia * std::numbers::pi / 180;
  c.X = S.fd_column(S.base, "reversal_spike", j, coulomb_key(j), std::max(h, 0.5));
  c.min_effect_ratio = m.loop_unresolved ? 1.0 : 0.0;
  return c;
}

Candidate backlash_candidate(const SignatureBasis& S, const JointMotion& m) {
  Candidate c = single_positive("backlash", m.j, m.ax, play_key(m.j));
  c.X = S.fd_column(S.base, "backlash", m.j, play_key(m.j), 1e-3);
  return c;
}

Candidate pitch_scale_candidate(const SignatureBasis& S, const JointMotion& m) {
  const int j = m.j;
  const auto* pitch = S.base.effects.pitch_error.active(j);
  const auto& motor = S.sim0.motor[j];
  Candidate c;
  c.effect = "pitch_error";
  c.joint = j;
  c.axis = m.ax;
  c.group = "pitch_error:" + m.ax + ":scale";
  c.keys = {"scale_um_per_m"};
  const double ref = pitch ? pitch->reference_mm : 0.0;
  std::vector<double> col(motor.size());
  for (std::size_t k = 0; k < motor.size(); ++k)
    col[k] = (motor[k] - ref) * 1e-6;
  c.X = S.column(j, col);
  c.apply = [j](sim::MachineParams& p, const VectorXd& coef) {
    enable_effect(p, "pitch_error", j);
    p.effects.pitch_error.axes[j]->scale_um_per_m += coef[0];
    return true;
  };
  return c;
}

// The believed period, else a scan of periods up to half the travel.
void add_pitch_periodic_candidates(const SignatureBasis& S, const JointMotion& m,
                                   std::vector<Candidate>& out) {
  const int j = m.j;
  const auto* pitch = S.base.effects.pitch_error.active(j);
  const auto& motor = S.sim0.motor[j];
  std::vector<double> periods;
  if (pitch && pitch->periodic_amplitude_um > 0) {
    periods.push_back(pitch->periodic_period_mm);
  } else {
    for (double p = 1.0; p <= 200.0; p *= 1.05)
      if (p <= m.travel / 2) periods.push_back(std::round(p * 1000) / 1000);
  }
  for (double P : periods) {
    Candidate c;
    c.effect = "pitch_error";
    c.joint = j;
    c.axis = m.ax;
    c.group = "pitch_error:" + m.ax + ":periodic";
    c.variant = "periodic_period_mm=" + fmt4g(P);
    c.keys = {"periodic_amplitude_um", "periodic_phase_deg", "periodic_period_mm"};
    std::vector<double> sn(motor.size()), cs(motor.size());
    for (std::size_t k = 0; k < motor.size(); ++k) {
      const double ph = 2 * std::numbers::pi * motor[k] / P;
      sn[k] = std::sin(ph) * 1e-3;
      cs[k] = std::cos(ph) * 1e-3;
    }
    c.X.resize(S.s0.size(), 2);
    c.X.col(0) = S.column(j, sn);
    c.X.col(1) = S.column(j, cs);
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

// A thermal-drift candidate of joint m.j: time constant tau, the driver
// (with its reference power when driven by the spindle power) and `col`, the
// first-order response to the driver at each row.
Candidate thermal_candidate(const SignatureBasis& S, const JointMotion& m, double tau,
                            sim::ThermalDriver driver, std::optional<double> reference_power_kw,
                            std::string variant, const std::vector<double>& col) {
  const int j = m.j;
  Candidate c;
  c.effect = "thermal_drift";
  c.joint = j;
  c.axis = m.ax;
  c.group = "thermal_drift:" + m.ax;
  c.variant = std::move(variant);
  c.keys = {"gain_mm", "tau_s"};
  c.X = S.column(j, col);
  c.apply = [j, tau, driver, reference_power_kw](sim::MachineParams& p, const VectorXd& coef) {
    enable_effect(p, "thermal_drift", j);
    auto& e = *p.effects.thermal_drift.axes[j];
    e.gain_mm = coef[0];
    e.tau_s = tau;
    e.driver = driver;
    if (reference_power_kw) e.reference_power_kw = *reference_power_kw;
    return true;
  };
  return c;
}

// Thermal drift driven by time: a first-order rise with a scan of time constants.
void add_thermal_time_candidates(const SignatureBasis& S, const JointMotion& m, double span_t,
                                 std::vector<Candidate>& out) {
  const double t0 = S.tr.t_s.front();
  for (double f : {0.03, 0.1, 0.3, 1.0, 3.0}) {
    const double tau = std::round(span_t * f * 1000) / 1000;
    if (!(tau > 0)) continue;
    std::vector<double> col(S.tr.rows());
    for (std::size_t k = 0; k < col.size(); ++k)
      col[k] = -std::expm1(-(S.tr.t_s[k] - t0) / tau);
    out.push_back(thermal_candidate(S, m, tau, sim::ThermalDriver::kTime, std::nullopt,
                                    "tau_s=" + fmt4g(tau), col));
  }
}

// Driven by the spindle power (u = P / P_ref, P_ref 10 kW): the
// first-order response to the recorded power, integrated exactly.
void add_thermal_power_candidates(const SignatureBasis& S, const JointMotion& m, double span_t,
                                  std::vector<Candidate>& out) {
  const Trace& tr = S.tr;
  const auto& pw = tr.spindle_power_kw;
  const bool powered =
      !pw.empty() && std::any_of(pw.begin(), pw.end(), [](double v) { return v > 0; });
  for (double f : {0.03, 0.1, 0.3, 1.0, 3.0}) {
    const double tau = std::round(span_t * f * 1000) / 1000;
    if (!powered || !(tau > 0)) continue;
    constexpr double kRefKw = 10.0;
    std::vector<double> col(tr.rows(), 0.0);
    for (std::size_t k = 1; k < col.size(); ++k)
      col[k] = col[k - 1] +
               (pw[k - 1] / kRefKw - col[k - 1]) * -std::expm1(-(tr.t_s[k] - tr.t_s[k - 1]) / tau);
    out.push_back(thermal_candidate(S, m, tau, sim::ThermalDriver::kSpindlePower, kRefKw,
                                    "driver=spindle_power tau_s=" + fmt4g(tau), col));
  }
}

// Every candidate of one joint, in a fixed order.
void add_joint_candidates(const SignatureBasis& S, const JointMotion& m, double span_t,
                          std::vector<Candidate>& out) {
  out.push_back(servo_lag_candidate(S, m));
  if (m.dynamic) out.push_back(reversal_spike_candidate(S, m));
  if (!S.tr.meas[m.j]) return;  // the encoder sees only the servo effects
  out.push_back(backlash_candidate(S, m));
  if (m.j >= 3) return;
  out.push_back(pitch_scale_candidate(S, m));
  add_pitch_periodic_candidates(S, m, out);
  if (!S.base.effects.thermal_drift.active(m.j) && span_t > 0) {
    add_thermal_time_candidates(S, m, span_t, out);
    add_thermal_power_candidates(S, m, span_t, out);
  }
}

// A squareness candidate of the model moves axis `dir` with the position of
// axis `moving`: xy (x with y), yz (y with z), zx (x with z).
bool squareness_pair(int dir, int moving) {
  return (dir == sim::kX && moving == sim::kY) || (dir == sim::kY && moving == sim::kZ) ||
         (dir == sim::kX && moving == sim::kZ);
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
void add_straightness_candidates(const SignatureBasis& S, std::vector<Candidate>& out) {
  const Trace& tr = S.tr;
  const Layout& L = S.L;
  const auto& base = S.base;
  const auto& sim0 = S.sim0;
  const auto& s0 = S.s0;
  auto column = [&S](int joint, const std::vector<double>& values) {
    return S.column(joint, values);
  };
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
    // Where a squareness moves the same axis with the same moving axis
    // (exy: x with y as squareness xy, exz as zx, eyz as yz), a bow whose
    // flat point may move is the same family of curves as a bow about a
    // fixed point plus that squareness, q (s − r)² = q (s − r₀)² − 2q(r − r₀) s
    // + const: the data cannot tell them apart, and a flat point fitted
    // from the slope goes anywhere (a small squareness on circles was named
    // a straightness with its flat point inside, or 62 m outside, the
    // travel). There the slope is the squareness's and the bow keeps its
    // reference; the flat point moves only where nothing else carries a
    // slope of that pair.
    const bool slope_is_squareness = squareness_pair(dir, moving);
    const bool move_ref = (!has || (*believed)->cubic_um_per_m3 == 0.0) && !slope_is_squareness;
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
}

// squareness: the error of one axis grows with the position of another.
void add_squareness_candidates(const SignatureBasis& S, std::vector<Candidate>& out) {
  const Trace& tr = S.tr;
  const Layout& L = S.L;
  const auto& sim0 = S.sim0;
  auto column = [&S](int joint, const std::vector<double>& values) {
    return S.column(joint, values);
  };
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
}

}  // namespace

std::vector<Candidate> build_candidates(const FitContext& ctx, const sim::MachineParams& base) {
  const SignatureBasis S(ctx, base);
  const Trace& tr = *ctx.trace;
  std::vector<Candidate> out;
  const double span_t = tr.t_s.back() - tr.t_s.front();
  const double sample_period_s = median_period(tr.t_s);
  for (int j : ctx.layout.axes) {
    const JointMotion m = joint_motion(S, j, sample_period_s);
    if (m.v_max > 0) {
      add_joint_candidates(S, m, span_t, out);
    } else if (tr.meas[j] && j < 3 && !S.base.effects.thermal_drift.active(j) && span_t > 0) {
      // The joint never moves: only a drift of its measured position can
      // show (a thermal growth does not need the axis to be commanded).
      add_thermal_time_candidates(S, m, span_t, out);
      add_thermal_power_candidates(S, m, span_t, out);
    }
  }
  add_straightness_candidates(S, out);
  add_squareness_candidates(S, out);
  return out;
}

}  // namespace truecut::analysis::diagnosis
