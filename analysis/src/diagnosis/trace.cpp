#include "trace.hpp"

#include <algorithm>
#include <cmath>

#include "truecut/sim/machine_model.hpp"

namespace truecut::analysis::diagnosis {

std::vector<double> command_slopes(const std::vector<double>& t, const std::vector<double>& y) {
  const std::size_t n = y.size();
  std::vector<double> m(n, 0.0);
  if (n < 2) return m;
  std::vector<double> secant(n - 1);
  for (std::size_t k = 0; k + 1 < n; ++k)
    secant[k] = (y[k + 1] - y[k]) / (t[k + 1] - t[k]);
  m[0] = secant[0];
  m[n - 1] = secant[n - 2];
  std::vector<char> turn(n, 0);
  for (std::size_t k = 1; k + 1 < n; ++k) {
    const double d0 = secant[k - 1], d1 = secant[k];
    if (d0 == 0 || d1 == 0) continue;  // next to a standstill: the motion starts or stops here
    const double h0 = t[k] - t[k - 1], h1 = t[k + 1] - t[k];
    m[k] = (h0 * d1 + h1 * d0) / (h0 + h1);
    turn[k] = d0 * d1 < 0;
  }
  // Fritsch–Carlson on the monotone stretches: no overshoot between two
  // samples that do not enclose a turn.
  for (std::size_t k = 0; k + 1 < n; ++k) {
    const double d = secant[k];
    if (d == 0) {
      m[k] = m[k + 1] = 0.0;
      continue;
    }
    if (turn[k] || turn[k + 1]) continue;
    const double a = m[k] / d, b = m[k + 1] / d, r2 = a * a + b * b;
    if (r2 > 9.0) {
      const double tau = 3.0 / std::sqrt(r2);
      m[k] = tau * a * d;
      m[k + 1] = tau * b * d;
    }
  }
  return m;
}

Trace make_trace(const Recording& rec, DiagnosisOptions::CommandInterpolation interpolation) {
  Trace tr;
  tr.file = rec.file;
  tr.t_s = rec.t_s;
  for (int j = 0; j < sim::kJointCount; ++j) {
    const std::string name(sim::kJointNames[j]);
    if (rec.has(name + "_cmd")) {
      tr.cmd[j] = rec.channel(name + "_cmd");
      if (interpolation == DiagnosisOptions::CommandInterpolation::kCubic)
        tr.cmd_slope[j] = command_slopes(tr.t_s, tr.cmd[j]);
    }
    if (rec.has(name + "_meas")) {
      tr.target[j] = rec.channel(name + "_meas");
      tr.meas[j] = true;
    } else if (rec.has(name + "_act")) {
      tr.target[j] = rec.channel(name + "_act");
    }
    if (!tr.cmd[j].empty() && !tr.target[j].empty()) tr.axes.push_back(j);
    tr.joint_pos[j] = !tr.target[j].empty() ? tr.target[j] : tr.cmd[j];
  }
  if (rec.has("tcp_true_x") && rec.has("tcp_true_y") && rec.has("tcp_true_z"))
    for (int i = 0; i < 3; ++i)
      tr.tcp[i] = rec.channel(std::string("tcp_true_") + "xyz"[i]);
  if (rec.has("spindle_power")) tr.spindle_power_kw = rec.channel("spindle_power");
  if (rec.has("line")) tr.line = rec.channel("line");
  if (rec.has("tool")) tr.tool = rec.channel("tool");
  return tr;
}

int substeps_for(double dt_s, double max_period_s) {
  if (!(dt_s > 0.0) || !(max_period_s > 0.0)) return 1;
  return std::clamp(int(std::ceil(dt_s / max_period_s - 1e-9)), 1, 100000);
}

double servo_periods_per_run(const Recording& rec, double max_servo_period_s) {
  double periods = 0;
  for (std::size_t k = 1; k < rec.t_s.size(); ++k)
    periods += substeps_for(rec.t_s[k] - rec.t_s[k - 1], max_servo_period_s);
  return periods;
}

namespace {

template <class Axis>
void copy_joint(sim::PerAxisEffect<Axis>& to, const sim::PerAxisEffect<Axis>& from, int j) {
  if (const Axis* a = from.active(j)) {
    to.enabled = true;
    to.axes[j] = *a;
  }
}

}  // namespace

sim::MachineParams joint_part(const sim::MachineParams& params, int j) {
  sim::MachineParams p;
  p.joints[j] = params.joints[j];
  const sim::Effects& fx = params.effects;
  copy_joint(p.effects.servo_lag, fx.servo_lag, j);
  copy_joint(p.effects.backlash, fx.backlash, j);
  copy_joint(p.effects.reversal_spike, fx.reversal_spike, j);
  copy_joint(p.effects.pitch_error, fx.pitch_error, j);
  copy_joint(p.effects.thermal_drift, fx.thermal_drift, j);
  return p;
}

void ResimCache::bind(const Trace& trace, double max_period_s) {
  if (trace_ == &trace && rows_ == trace.rows() && max_period_s_ == max_period_s) return;
  trace_ = &trace;
  rows_ = trace.rows();
  max_period_s_ = max_period_s;
  const std::size_t run_bytes = sizeof(Run) + 2 * sizeof(double) * std::max<std::size_t>(rows_, 1);
  capacity_ = std::min(max_runs_, std::max(kMinRuns, kBytesPerJoint / run_bytes));
  for (auto& r : runs_)
    r.clear();
}

std::shared_ptr<const ResimCache::Run> ResimCache::find(const Trace& trace, double max_period_s,
                                                        int j, const sim::MachineParams& key) {
  const std::lock_guard lock(mutex_);
  bind(trace, max_period_s);
  auto& runs = runs_[std::size_t(j)];
  for (auto it = runs.rbegin(); it != runs.rend(); ++it)
    if ((*it)->key == key) {
      auto run = *it;
      runs.erase(std::next(it).base());
      runs.push_back(run);
      return run;
    }
  return nullptr;
}

void ResimCache::put(const Trace& trace, double max_period_s, int j,
                     std::shared_ptr<const Run> run) {
  const std::lock_guard lock(mutex_);
  bind(trace, max_period_s);
  auto& runs = runs_[std::size_t(j)];
  if (runs.size() >= capacity_) runs.erase(runs.begin());
  runs.push_back(std::move(run));
}

namespace {

// Joint j through the model over the whole trace: the encoder (motor) and
// the table-side (true) position at every sample.
void simulate_joint(const sim::MachineModel& model, const Trace& tr, int j, double max_period_s,
                    double nominal_dt, std::vector<double>& motor, std::vector<double>& truth) {
  const std::size_t n = tr.rows();
  motor.resize(n);
  truth.resize(n);
  sim::MachineState state;
  sim::MachineOutputs out;
  // The command of joint j at fraction s of the interval k → k1 of length dt.
  auto cmd_at = [&](std::size_t k, std::size_t k1, double s, double dt) {
    if (tr.cmd[j].empty()) return 0.0;
    const double p0 = tr.cmd[j][k], p1 = tr.cmd[j][k1];
    if (s == 0.0 || k1 == k) return p0;
    if (tr.cmd_slope[j].empty()) return p0 + (p1 - p0) * s;
    const double s2 = s * s, s3 = s2 * s;
    return (2 * s3 - 3 * s2 + 1) * p0 + (s3 - 2 * s2 + s) * dt * tr.cmd_slope[j][k] +
           (3 * s2 - 2 * s3) * p1 + (s3 - s2) * dt * tr.cmd_slope[j][k1];
  };
  for (std::size_t k = 0; k < n; ++k) {
    double dt = k + 1 < n ? tr.t_s[k + 1] - tr.t_s[k] : (n > 1 ? tr.t_s[k] - tr.t_s[k - 1] : 1e-3);
    // Time stamps printed or summed in floating point jitter by parts in
    // 10⁹ about the recorder's period; the servo steps at the period itself.
    if (std::abs(dt - nominal_dt) <= 1e-6 * nominal_dt) dt = nominal_dt;
    const int sub = substeps_for(dt, max_period_s);
    const std::size_t k1 = std::min(k + 1, n - 1);
    const double power = tr.spindle_power_kw.empty() ? 0.0 : tr.spindle_power_kw[k];
    for (int i = 0; i < sub; ++i) {
      const double w = double(i) / sub;
      model.step_joint(j, state, cmd_at(k, k1, w, dt), power, dt / sub, out);
      if (i != 0) continue;
      motor[k] = out.pos_act[j];
      truth[k] = out.pos_true[j];
    }
  }
}

}  // namespace

Simulated resimulate(const sim::MachineParams& params, const Trace& tr, double max_period_s,
                     ResimCache* cache) {
  const sim::MachineModel model(params);
  Simulated sim;
  const std::size_t n = tr.rows();
  for (int j : tr.axes) {
    sim.target[j].resize(n);
    sim.motor[j].resize(n);
  }
  // Joints without a target may still be needed (cross-axis signatures).
  for (int j = 0; j < sim::kJointCount; ++j)
    if (sim.motor[j].empty() && !tr.cmd[j].empty()) sim.motor[j].resize(n);
  // The joints to run: those with an output, and every linear slide when a
  // slide's true position is recorded (the geometric errors couple them).
  std::array<bool, sim::kJointCount> need{};
  bool slides = false;
  for (int j = 0; j < sim::kJointCount; ++j) {
    need[j] = !sim.motor[j].empty() || !sim.target[j].empty();
    slides = slides || (j < 3 && !sim.target[j].empty() && tr.meas[j]);
  }
  if (slides) need[sim::kX] = need[sim::kY] = need[sim::kZ] = true;
  const double nominal_dt = median_period(tr.t_s);
  std::array<std::shared_ptr<const ResimCache::Run>, sim::kJointCount> run;
  for (int j = 0; j < sim::kJointCount; ++j) {
    if (!need[j]) continue;
    const sim::MachineParams key = cache ? joint_part(params, j) : sim::MachineParams{};
    if (cache) run[j] = cache->find(tr, max_period_s, j, key);
    if (run[j]) continue;
    auto r = std::make_shared<ResimCache::Run>();
    simulate_joint(model, tr, j, max_period_s, nominal_dt, r->motor, r->truth);
    r->key = key;
    if (cache) cache->put(tr, max_period_s, j, r);
    run[j] = std::move(r);
  }
  const auto* squareness = params.effects.squareness.active();
  const auto* straightness = params.effects.straightness.active();
  for (int j = 0; j < sim::kJointCount; ++j) {
    if (!sim.motor[j].empty()) sim.motor[j] = run[j]->motor;
    if (sim.target[j].empty()) continue;
    if (!tr.meas[j]) {
      sim.target[j] = run[j]->motor;
    } else if (j >= 3) {
      sim.target[j] = run[j]->truth;
    } else {
      const auto& x = run[sim::kX]->truth;
      const auto& y = run[sim::kY]->truth;
      const auto& z = run[sim::kZ]->truth;
      for (std::size_t k = 0; k < n; ++k)
        sim.target[j][k] =
            sim::apply_geometric_errors(squareness, straightness, {x[k], y[k], z[k]})[j];
    }
  }
  return sim;
}

std::vector<double> delayed(const std::vector<double>& t, const std::vector<double>& y,
                            double delay_s) {
  if (delay_s == 0.0 || y.empty()) return y;
  const std::size_t n = t.size();
  const std::vector<double> m = command_slopes(t, y);
  std::vector<double> out(n);
  std::size_t i = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const double tq = std::clamp(t[k] - delay_s, t.front(), t.back());
    while (i + 1 < n && t[i + 1] < tq)
      ++i;
    while (i > 0 && t[i] > tq)
      --i;
    const std::size_t i1 = std::min(i + 1, n - 1);
    const double h = t[i1] - t[i];
    const double s = h > 0 ? (tq - t[i]) / h : 0.0;
    const double s2 = s * s, s3 = s2 * s;
    out[k] = (2 * s3 - 3 * s2 + 1) * y[i] + (s3 - 2 * s2 + s) * h * m[i] +
             (3 * s2 - 2 * s3) * y[i1] + (s3 - s2) * h * m[i1];
  }
  return out;
}

void delay_simulated(const std::vector<double>& t, Simulated& sim, double delay_s) {
  if (delay_s == 0.0) return;
  for (auto& v : sim.target)
    v = delayed(t, v, delay_s);
  for (auto& v : sim.motor)
    v = delayed(t, v, delay_s);
}

std::vector<double> derivative(const std::vector<double>& t, const std::vector<double>& y) {
  const std::size_t n = t.size();
  std::vector<double> d(n, 0.0);
  if (n < 2) return d;
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t a = k == 0 ? 0 : k - 1, b = k + 1 < n ? k + 1 : n - 1;
    d[k] = (y[b] - y[a]) / (t[b] - t[a]);
  }
  return d;
}

double median_period(const std::vector<double>& t) {
  if (t.size() < 2) return 0.0;
  std::vector<double> d(t.size() - 1);
  for (std::size_t k = 0; k + 1 < t.size(); ++k)
    d[k] = t[k + 1] - t[k];
  std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
  return d[d.size() / 2];
}

}  // namespace truecut::analysis::diagnosis
