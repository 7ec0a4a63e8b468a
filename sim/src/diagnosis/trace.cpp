#include "trace.hpp"

#include <algorithm>
#include <cmath>

#include "truecut/sim/machine_model.hpp"

namespace truecut::sim::diagnosis {

Trace make_trace(const Recording& rec) {
  Trace tr;
  tr.file = rec.file;
  tr.t_s = rec.t_s;
  for (int j = 0; j < kJointCount; ++j) {
    const std::string name(kJointNames[j]);
    if (rec.has(name + "_cmd")) tr.cmd[j] = rec.channel(name + "_cmd");
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

Simulated resimulate(const MachineParams& params, const Trace& tr, double max_period_s) {
  const MachineModel model(params);
  MachineState state;
  MachineInputs in;
  MachineOutputs out;
  Simulated sim;
  const std::size_t n = tr.rows();
  for (int j : tr.axes) {
    sim.target[j].resize(n);
    sim.motor[j].resize(n);
  }
  // Joints without a target may still be needed (cross-axis signatures).
  for (int j = 0; j < kJointCount; ++j)
    if (sim.motor[j].empty() && !tr.cmd[j].empty()) sim.motor[j].resize(n);
  auto cmd_at = [&](int j, std::size_t k) { return tr.cmd[j].empty() ? 0.0 : tr.cmd[j][k]; };
  for (std::size_t k = 0; k < n; ++k) {
    const double dt =
        k + 1 < n ? tr.t_s[k + 1] - tr.t_s[k] : (n > 1 ? tr.t_s[k] - tr.t_s[k - 1] : 1e-3);
    const int sub = substeps_for(dt, max_period_s);
    const std::size_t k1 = std::min(k + 1, n - 1);
    for (int i = 0; i < sub; ++i) {
      const double w = double(i) / sub;
      for (int j = 0; j < kJointCount; ++j)
        in.pos_cmd[j] = cmd_at(j, k) + (cmd_at(j, k1) - cmd_at(j, k)) * w;
      in.spindle_power_kw = tr.spindle_power_kw.empty() ? 0.0 : tr.spindle_power_kw[k];
      model.step(state, in, dt / sub, out);
      if (i != 0) continue;
      for (int j = 0; j < kJointCount; ++j) {
        if (!sim.motor[j].empty()) sim.motor[j][k] = out.pos_act[j];
        if (sim.target[j].empty()) continue;
        if (!tr.meas[j])
          sim.target[j][k] = out.pos_act[j];
        else
          sim.target[j][k] = j < 3 ? out.xyz_true[j] : out.pos_true[j];
      }
    }
  }
  return sim;
}

std::vector<double> delayed(const std::vector<double>& t, const std::vector<double>& y,
                            double delay_s) {
  if (delay_s == 0.0 || y.empty()) return y;
  const std::size_t n = t.size();
  std::vector<double> out(n);
  std::size_t i = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const double tq = std::clamp(t[k] - delay_s, t.front(), t.back());
    while (i + 1 < n && t[i + 1] < tq)
      ++i;
    while (i > 0 && t[i] > tq)
      --i;
    const std::size_t i1 = std::min(i + 1, n - 1);
    const double span = t[i1] - t[i];
    const double w = span > 0 ? (tq - t[i]) / span : 0.0;
    out[k] = y[i] + (y[i1] - y[i]) * w;
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

}  // namespace truecut::sim::diagnosis
