#include "tcp_stage.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>

#include "effect_params.hpp"
#include "locate.hpp"
#include "truecut/sim/true_tool_pose.hpp"

namespace truecut::analysis::diagnosis {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// The candidate parameters; the step is the central-difference half step
// (1 µm, 1 µrad, 1 µm of tool length).
struct TcpParam {
  const char* effect;
  const char* key;
  double step;
};
constexpr TcpParam kParams[] = {
    {"rotary_location", "a.e_y0a_um", 1.0},   {"rotary_location", "a.e_z0a_um", 1.0},
    {"rotary_location", "a.e_b0a_urad", 1.0}, {"rotary_location", "a.e_c0a_urad", 1.0},
    {"rotary_location", "a.e_a0a_urad", 1.0}, {"rotary_location", "c.e_x0c_um", 1.0},
    {"rotary_location", "c.e_y0c_um", 1.0},   {"rotary_location", "c.e_a0c_urad", 1.0},
    {"rotary_location", "c.e_b0c_urad", 1.0}, {"rotary_location", "c.e_c0c_urad", 1.0},
    {"tool_length_error", "length_mm", 1e-3},
};
constexpr int kParamCount = int(std::size(kParams));

// The parameter in `m`, its effect switched on (from zero when it was off).
double& param_ref(sim::MachineParams& m, const TcpParam& p) {
  sim::Effects& e = m.effects;
  const std::string key = p.key;
  if (std::string(p.effect) == "tool_length_error") {
    if (!e.tool_length_error.enabled) e.tool_length_error.params = {};
    e.tool_length_error.enabled = true;
    return e.tool_length_error.params.length_mm;
  }
  if (!e.rotary_location.enabled) e.rotary_location.params = {};
  e.rotary_location.enabled = true;
  auto& a = e.rotary_location.params.a;
  auto& c = e.rotary_location.params.c;
  if (key == "a.e_y0a_um") return a.e_y0a_um;
  if (key == "a.e_z0a_um") return a.e_z0a_um;
  if (key == "a.e_b0a_urad") return a.e_b0a_urad;
  if (key == "a.e_c0a_urad") return a.e_c0a_urad;
  if (key == "a.e_a0a_urad") return a.e_a0a_urad;
  if (key == "c.e_x0c_um") return c.e_x0c_um;
  if (key == "c.e_y0c_um") return c.e_y0c_um;
  if (key == "c.e_a0c_urad") return c.e_a0c_urad;
  if (key == "c.e_b0c_urad") return c.e_b0c_urad;
  return c.e_c0c_urad;
}

// The parameter's value in `base` (0 when its effect is off).
double value_in(const sim::MachineParams& base, const TcpParam& p) {
  const bool on = std::string(p.effect) == "tool_length_error"
                      ? base.effects.tool_length_error.enabled
                      : base.effects.rotary_location.enabled;
  if (!on) return 0.0;
  sim::MachineParams m = base;
  return param_ref(m, p);
}

std::string label(const TcpParam& p) {
  return std::string(p.effect) == "tool_length_error" ? "tool_length_error"
                                                      : std::string(p.effect) + "." + p.key;
}

std::string separation(const TcpParam& p, const TcpParam& q, bool datum_known) {
  const std::string a = label(p), b = label(q);
  auto has = [&](const char* x, const char* y) { return (a == x && b == y) || (a == y && b == x); };
  if (has("tool_length_error", "rotary_location.a.e_z0a_um") && !datum_known)
    return "the TCP measured against a datum fixed in the workpiece frame (--tcp-datum known), "
           "or the tool length measured on its own (presetter): with the measurement's constant "
           "offset unknown, a tool-length error and a Z offset of the A axis line move the TCP "
           "alike at every A and C";
  if (std::string(p.effect) != q.effect) return separation_hint(p.effect, q.effect);
  return "a motion that turns A and C independently over larger angles, with the TCP at several "
         "distances from the axis lines";
}

// The rows of a mask.
std::vector<std::size_t> rows_of(const std::vector<char>& mask) {
  std::vector<std::size_t> r;
  for (std::size_t k = 0; k < mask.size(); ++k)
    if (mask[k]) r.push_back(k);
  return r;
}

// The nominal tool length of each row (NaN: the description's tool).
std::vector<double> tool_lengths(const Trace& tr, const std::map<int, double>& table) {
  std::vector<double> out(tr.rows(), std::numeric_limits<double>::quiet_NaN());
  if (table.empty()) return out;
  for (std::size_t k = 0; k < tr.rows(); ++k) {
    if (tr.tool.empty()) {
      if (table.size() == 1) out[k] = table.begin()->second;
      continue;
    }
    const auto it = table.find(int(std::lround(tr.tool[k])));
    if (it != table.end()) out[k] = it->second;
  }
  return out;
}

// The TCP through m's kinematics for each row, stacked x block, y, z.
VectorXd predict(const Trace& tr, const std::vector<std::size_t>& rows, const sim::MachineParams& m,
                 const std::vector<double>& nominal_length_mm) {
  const sim::TrueKinematics k0 = sim::true_kinematics(m);
  // The true length is the nominal one plus the description's length error.
  const double error_mm = k0.tool_length_mm - m.kinematics.tool.length_mm;
  sim::TrueKinematics k = k0;
  const std::size_t n = rows.size();
  VectorXd out(Eigen::Index(3 * n));
  auto q = [&](int j, std::size_t row) {
    return tr.joint_pos[j].empty() ? 0.0 : tr.joint_pos[j][row];
  };
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t row = rows[i];
    const double nominal = nominal_length_mm[row];
    k.tool_length_mm = std::isnan(nominal) ? k0.tool_length_mm : nominal + error_mm;
    const auto pose = sim::true_tool_pose(k, {q(sim::kX, row), q(sim::kY, row), q(sim::kZ, row)},
                                          q(sim::kA, row), q(sim::kC, row));
    for (int c = 0; c < 3; ++c)
      out[Eigen::Index(c * n + i)] = pose.tcp_mm[c];
  }
  return out;
}

VectorXd measured(const Trace& tr, const std::vector<std::size_t>& rows) {
  const std::size_t n = rows.size();
  VectorXd out(Eigen::Index(3 * n));
  for (int c = 0; c < 3; ++c)
    for (std::size_t i = 0; i < n; ++i)
      out[Eigen::Index(c * n + i)] = tr.tcp[c][rows[i]];
  return out;
}

// Per-component means of a stacked vector.
std::array<double, 3> means(const VectorXd& v) {
  const Eigen::Index n = v.size() / 3;
  std::array<double, 3> m{};
  for (int c = 0; c < 3; ++c)
    m[c] = n ? v.segment(c * n, n).mean() : 0.0;
  return m;
}

struct Weights {
  std::array<double, 3> w{1, 1, 1};
  bool center = true;
  // Weighted and (with an unknown datum) centred per component.
  VectorXd apply(VectorXd v) const {
    const Eigen::Index n = v.size() / 3;
    const auto m = means(v);
    for (int c = 0; c < 3; ++c)
      v.segment(c * n, n) = (v.segment(c * n, n).array() - (center ? m[c] : 0.0)) * w[c];
    return v;
  }
};

double lag1(const VectorXd& v) {
  const Eigen::Index n = v.size() / 3;
  double num = 0, den = 0;
  for (int c = 0; c < 3; ++c)
    for (Eigen::Index i = 0; i < n; ++i) {
      const double x = v[c * n + i];
      den += x * x;
      if (i > 0) num += x * v[c * n + i - 1];
    }
  return den > 0 ? num / den : 0.0;
}

double rss_after(const MatrixXd& x, const VectorXd& y, VectorXd* coef = nullptr) {
  if (x.cols() == 0) return y.squaredNorm();
  Eigen::ColPivHouseholderQR<MatrixXd> qr(x);
  qr.setThreshold(1e-10);
  const VectorXd b = qr.solve(y);
  if (coef) *coef = b;
  return (y - x * b).squaredNorm();
}

sim::MachineParams with_theta(const sim::MachineParams& base, const std::vector<int>& sel,
                              const VectorXd& theta) {
  sim::MachineParams m = base;
  for (std::size_t i = 0; i < sel.size(); ++i)
    param_ref(m, kParams[sel[i]]) = theta[Eigen::Index(i)];
  return m;
}

// ∂(weighted, centred TCP)/∂parameter at m (central differences).
VectorXd column(const Trace& tr, const std::vector<std::size_t>& rows, const sim::MachineParams& m,
                const std::vector<double>& len, const TcpParam& p, const Weights& w) {
  sim::MachineParams up = m, down = m;
  const double v = value_in(m, p);
  param_ref(up, p) = v + p.step;
  param_ref(down, p) = v - p.step;
  return w.apply((predict(tr, rows, up, len) - predict(tr, rows, down, len)) / (2 * p.step));
}

void figures(const VectorXd& before, const VectorXd& after, FitFigures& f) {
  const Eigen::Index n = before.size() / 3;
  f.samples = std::size_t(before.size());
  f.rms_before_mm = f.rms_unaligned_mm = std::sqrt(before.squaredNorm() / double(before.size()));
  f.rms_after_mm = std::sqrt(after.squaredNorm() / double(after.size()));
  f.max_before_mm = before.cwiseAbs().maxCoeff();
  f.max_after_mm = after.cwiseAbs().maxCoeff();
  for (int c = 0; c < 3; ++c)
    f.per_axis_rms_mm[std::string("tcp_") + "xyz"[c]] = {
        std::sqrt(before.segment(c * n, n).squaredNorm() / double(n)),
        std::sqrt(after.segment(c * n, n).squaredNorm() / double(n))};
}

// The noise the recording's resolution puts into the TCP residual, per
// component: the measured TCP's own grid step and the joints' grid steps
// carried through the kinematics (RMS of ∂tcp/∂joint over the rows), each
// quantisation uniform (q/√12). Zero for continuous, noisy channels.
std::array<double, 3> quantisation_noise(const Trace& tr, const std::vector<char>& use,
                                         const sim::MachineParams& m,
                                         const std::vector<double>& len) {
  std::array<double, 3> var{};
  for (int c = 0; c < 3; ++c) {
    const double q = grid_step(tr.tcp[c], use);
    var[c] += q * q / 12.0;
  }
  const auto rows = rows_of(use);
  if (rows.empty()) return {std::sqrt(var[0]), std::sqrt(var[1]), std::sqrt(var[2])};
  // The joints at most 500 rows spread over the block, for their sensitivities.
  Trace few;
  std::vector<double> few_len;
  const std::size_t stride = std::max<std::size_t>(1, rows.size() / 500);
  for (int j = 0; j < sim::kJointCount; ++j)
    if (!tr.joint_pos[j].empty())
      for (std::size_t i = 0; i < rows.size(); i += stride)
        few.joint_pos[j].push_back(tr.joint_pos[j][rows[i]]);
  for (std::size_t i = 0; i < rows.size(); i += stride)
    few_len.push_back(len[rows[i]]);
  std::vector<std::size_t> sample(few_len.size());
  for (std::size_t i = 0; i < sample.size(); ++i)
    sample[i] = i;
  const Eigen::Index n = Eigen::Index(sample.size());
  for (int j = 0; j < sim::kJointCount; ++j) {
    if (tr.joint_pos[j].empty()) continue;
    const double q = grid_step(tr.joint_pos[j], use);
    if (q <= 0) continue;
    constexpr double h = 1e-3;  // mm or deg
    Trace up = few, down = few;
    for (auto& v : up.joint_pos[j])
      v += h;
    for (auto& v : down.joint_pos[j])
      v -= h;
    const VectorXd d =
        (predict(up, sample, m, few_len) - predict(down, sample, m, few_len)) / (2 * h);
    for (int c = 0; c < 3; ++c)
      var[c] += d.segment(c * n, n).squaredNorm() / double(n) * q * q / 12.0;
  }
  std::array<double, 3> out{};
  for (int c = 0; c < 3; ++c)
    out[c] = std::sqrt(var[c]);
  return out;
}

}  // namespace

TcpStage fit_tcp(const Trace& tr, const std::vector<char>& train,
                 const std::vector<char>& heldout_rows, const Trace* holdout,
                 const sim::MachineParams& base, const DiagnosisOptions& o) {
  auto say = [&](const std::string& s) {
    if (o.progress) o.progress(s);
  };
  TcpStage out;
  out.fitted = base;
  TcpComparison& cmp = out.comparison;
  cmp.datum_known = o.tcp_datum_known;
  const auto tr_rows = rows_of(train);
  if (!tr.has_tcp() || tr_rows.size() < 20) return out;
  cmp.present = true;
  const std::vector<double> len = tool_lengths(tr, o.tool_length_mm);
  say("comparing the measured tool-centre point with the believed kinematics");

  // Residual of the believed kinematics, its floor and constant offset.
  const VectorXd y = measured(tr, tr_rows);
  const VectorXd r0 = y - predict(tr, tr_rows, base, len);
  Weights w;
  w.center = !o.tcp_datum_known;
  {
    const auto all_rows = rows_of(std::vector<char>(tr.rows(), 1));
    const VectorXd all = measured(tr, all_rows) - predict(tr, all_rows, base, len);
    const auto resolution = quantisation_noise(tr, train, base, len);
    std::vector<double> full(tr.rows(), 0.0);
    const Eigen::Index N = Eigen::Index(tr.rows());
    for (int c = 0; c < 3; ++c) {
      for (Eigen::Index k = 0; k < N; ++k)
        full[std::size_t(k)] = all[c * N + k];
      cmp.noise_floor_mm[c] = std::max(noise_floor(full, train), resolution[c]);
      w.w[c] = 1.0 / std::max(cmp.noise_floor_mm[c], 1e-7);
    }
  }
  const auto off0 = means(r0);
  for (int c = 0; c < 3; ++c)
    cmp.offset_mm[c] = w.center ? off0[c] : 0.0;
  const VectorXd e0 = w.apply(r0);

  // Signatures at the believed model; parameters that move nothing dropped.
  std::vector<int> cand;
  std::vector<VectorXd> cols(kParamCount);
  for (int i = 0; i < kParamCount; ++i) {
    cols[i] = column(tr, tr_rows, base, len, kParams[i], w);
    if (cols[i].norm() * kParams[i].step / std::sqrt(double(cols[i].size())) < 1e-3) continue;
    cand.push_back(i);
    out.tested.push_back(label(kParams[i]));
  }
  auto design = [&](const std::vector<int>& sel) {
    MatrixXd x(e0.size(), Eigen::Index(sel.size()));
    for (std::size_t i = 0; i < sel.size(); ++i)
      x.col(Eigen::Index(i)) = cols[sel[i]];
    return x;
  };
  const double big_n = double(e0.size());
  double n_eff = big_n;
  {
    // Lag-1 autocorrelation of what every candidate together leaves.
    VectorXd coef;
    const MatrixXd x = design(cand);
    VectorXd rest = e0;
    if (x.cols()) {
      rss_after(x, e0, &coef);
      rest -= x * coef;
    }
    const double rho = std::clamp(lag1(rest), 0.0, 0.99);
    n_eff = std::max(2.0, big_n * (1 - rho) / (1 + rho));
  }
  const int k0 = w.center ? 3 : 0;
  auto bic = [&](const std::vector<int>& sel) {
    const double rss = rss_after(design(sel), e0);
    return n_eff * std::log(std::max(rss, 1e-300) / big_n) +
           double(k0 + int(sel.size())) * std::log(n_eff);
  };

  // Forward selection, one parameter at a time; a parameter whose share of
  // the joint fit is below min_effect_ratio of the floor is not physics
  // (weighted units: the floor is 1).
  std::vector<int> sel;
  std::set<int> too_small;
  std::map<int, double> gain;
  double current = bic(sel);
  for (;;) {
    int best = -1;
    double best_bic = current;
    for (int i : cand) {
      if (std::find(sel.begin(), sel.end(), i) != sel.end() || too_small.count(i)) continue;
      auto s = sel;
      s.push_back(i);
      const double b = bic(s);
      if (b < best_bic) best_bic = b, best = i;
    }
    if (best < 0 || current - best_bic <= o.bic_threshold) break;
    {
      auto s = sel;
      s.push_back(best);
      VectorXd coef;
      rss_after(design(s), e0, &coef);
      const VectorXd contrib = cols[best] * coef[coef.size() - 1];
      double ss = 0;
      Eigen::Index support = 0;
      const Eigen::Index n = contrib.size() / 3;
      for (int c = 0; c < 3; ++c)
        if (const double sc = contrib.segment(c * n, n).squaredNorm(); sc > 0)
          ss += sc, support += n;
      if (support == 0 || std::sqrt(ss / double(support)) < o.min_effect_ratio) {
        say("TCP: " + label(kParams[best]) + " passes the BIC but is below " +
            std::to_string(o.min_effect_ratio) + " of the noise floor; not selected");
        too_small.insert(best);
        continue;
      }
    }
    gain[best] = best_bic - current;
    say("TCP: selected " + label(kParams[best]) + " (ΔBIC " + std::to_string(best_bic - current) +
        ")");
    sel.push_back(best);
    current = best_bic;
  }

  // Not identifiable (a): a selected parameter a rival replaces within the threshold.
  for (int s : sel)
    for (int q : cand) {
      if (std::find(sel.begin(), sel.end(), q) != sel.end()) continue;
      auto alt = sel;
      std::replace(alt.begin(), alt.end(), s, q);
      if (bic(alt) - current >= o.bic_threshold) continue;
      const double corr = cols[s].dot(cols[q]) / std::max(1e-300, cols[s].norm() * cols[q].norm());
      out.not_identifiable.push_back({label(kParams[s]), label(kParams[q]), corr,
                                      separation(kParams[s], kParams[q], o.tcp_datum_known)});
    }

  // Gauss–Newton from the believed values (the kinematics are nearly linear
  // in these small errors; a few iterations).
  const Eigen::Index p = Eigen::Index(sel.size());
  VectorXd theta(p);
  for (Eigen::Index i = 0; i < p; ++i)
    theta[i] = value_in(base, kParams[sel[std::size_t(i)]]);
  MatrixXd cov = MatrixXd::Zero(p, p);
  for (int it = 0; p > 0 && it < 10; ++it) {
    const sim::MachineParams m = with_theta(base, sel, theta);
    const VectorXd e = w.apply(y - predict(tr, tr_rows, m, len));
    MatrixXd j(e.size(), p);
    for (Eigen::Index i = 0; i < p; ++i)
      j.col(i) = column(tr, tr_rows, m, len, kParams[sel[std::size_t(i)]], w);
    VectorXd delta;
    rss_after(j, e, &delta);
    // Per component its own residual variance and correlation inflation
    // (pooling would let a component the parameters do not move shrink the
    // interval): cov = (Σ_c J_cᵀJ_c / (s²_c f_c))⁻¹.
    const VectorXd rest = e - j * delta;
    const Eigen::Index nc = rest.size() / 3;
    MatrixXd info = MatrixXd::Zero(p, p);
    for (int c = 0; c < 3; ++c) {
      const auto seg = rest.segment(c * nc, nc);
      double num = 0;
      for (Eigen::Index i = 1; i < nc; ++i)
        num += seg[i] * seg[i - 1];
      const double den = seg.squaredNorm();
      const double rho = std::clamp(den > 0 ? num / den : 0.0, 0.0, 0.99);
      const double s2 = den / double(nc) * big_n / std::max(1.0, big_n - double(p + k0));
      const auto jc = j.middleRows(c * nc, nc);
      info += jc.transpose() * jc / std::max(s2 * (1 + rho) / (1 - rho), 1e-4);
    }
    cov = info.completeOrthogonalDecomposition().pseudoInverse();
    theta += delta;
    bool small = true;
    for (Eigen::Index i = 0; i < p; ++i)
      small = small && std::abs(delta[i]) <= 1e-3 * std::sqrt(std::max(cov(i, i), 1e-300));
    if (small) break;
  }
  out.fitted = with_theta(base, sel, theta);

  // Not identifiable (b): fitted parameters that are nearly one combination.
  for (Eigen::Index a = 0; a < p; ++a)
    for (Eigen::Index b = a + 1; b < p; ++b) {
      const double cc = cov(a, b) / std::sqrt(std::max(cov(a, a) * cov(b, b), 1e-300));
      if (std::abs(cc) >= 0.99) {
        const auto& pa = kParams[sel[std::size_t(a)]];
        const auto& pb = kParams[sel[std::size_t(b)]];
        out.not_identifiable.push_back(
            {label(pa), label(pb), cc, separation(pa, pb, o.tcp_datum_known)});
      }
    }

  // Explanations, one per effect.
  const VectorXd p_fit = predict(tr, tr_rows, out.fitted, len);
  for (const char* effect : {"rotary_location", "tool_length_error"}) {
    Explanation e;
    e.effect = effect;
    sim::MachineParams without = out.fitted;
    for (Eigen::Index i = 0; i < p; ++i) {
      const TcpParam& q = kParams[sel[std::size_t(i)]];
      if (std::string(q.effect) != effect) continue;
      const double se = std::sqrt(std::max(0.0, cov(i, i)));
      e.parameters.push_back({q.key, theta[i], theta[i] - 1.96 * se, theta[i] + 1.96 * se, false});
      e.delta_bic += gain[sel[std::size_t(i)]];
      param_ref(without, q) = value_in(base, q);
    }
    if (e.parameters.empty()) continue;
    if (std::string(effect) == "tool_length_error") {
      e.parameters.front().name = "length_mm";
    } else {
      e.note = "from the measured tool-centre point";
    }
    e.rms_effect_mm = std::sqrt((p_fit - predict(tr, tr_rows, without, len)).squaredNorm() /
                                double(p_fit.size()));
    out.explanations.push_back(e);
  }

  // Before / after on the fitted block and the held-out block (offsets of
  // the fitted block).
  auto remove = [&](VectorXd v, const std::array<double, 3>& off) {
    const Eigen::Index m = v.size() / 3;
    for (int c = 0; c < 3; ++c)
      v.segment(c * m, m).array() -= off[c];
    return v;
  };
  const VectorXd r1 = y - p_fit;
  std::array<double, 3> off1{};
  if (w.center) off1 = means(r1);
  const VectorXd before = remove(r0, cmp.offset_mm);
  figures(before, remove(r1, off1), cmp.train);
  // Located: per component, over the whole block and per 30° of A and C.
  {
    const Eigen::Index m = before.size() / 3;
    auto region = [&](int c, const std::string& what, const std::vector<Eigen::Index>& idx) {
      Mismatch g;
      g.axis = std::string("tcp_") + "xyz"[c];
      g.where = what == "whole recording" ? "axis" : "rotary_angle";
      g.what = what;
      g.samples = idx.size();
      double ss = 0, sum = 0;
      for (Eigen::Index i : idx) {
        const double v = before[c * m + i];
        ss += v * v, sum += v, g.max_mm = std::max(g.max_mm, std::abs(v));
      }
      if (idx.size() < 10) return;
      g.rms_mm = std::sqrt(ss / double(idx.size()));
      g.mean_mm = sum / double(idx.size());
      g.ratio_to_floor = g.rms_mm / std::max(cmp.noise_floor_mm[c], 1e-12);
      if (g.ratio_to_floor > 1.5) out.mismatch.push_back(g);
    };
    std::vector<Eigen::Index> all(static_cast<std::size_t>(m));
    for (Eigen::Index i = 0; i < m; ++i)
      all[std::size_t(i)] = i;
    for (int c = 0; c < 3; ++c)
      region(c, "whole recording", all);
    for (int j : {sim::kA, sim::kC}) {
      const auto& q = tr.joint_pos[j];
      if (q.empty()) continue;
      for (int b = 0; b < 12; ++b) {
        std::vector<Eigen::Index> idx;
        for (Eigen::Index i = 0; i < m; ++i) {
          const double deg = std::fmod(std::fmod(q[tr_rows[std::size_t(i)]], 360.0) + 360.0, 360.0);
          if (int(deg / 30.0) == b) idx.push_back(i);
        }
        if (idx.size() == all.size()) continue;  // the angle never changes
        const std::string what = std::string(sim::kJointNames[j]) + " " + std::to_string(30 * b) +
                                 "–" + std::to_string(30 * b + 30) + " deg";
        for (int c = 0; c < 3; ++c)
          region(c, what, idx);
      }
    }
  }
  const Trace& ht = holdout ? *holdout : tr;
  const auto ho_rows = holdout ? rows_of(std::vector<char>(ht.rows(), 1)) : rows_of(heldout_rows);
  if (!ho_rows.empty() && ht.has_tcp()) {
    const std::vector<double> ho_len = tool_lengths(ht, o.tool_length_mm);
    const VectorXd yh = measured(ht, ho_rows);
    figures(remove(yh - predict(ht, ho_rows, base, ho_len), cmp.offset_mm),
            remove(yh - predict(ht, ho_rows, out.fitted, ho_len), off1), cmp.heldout);
  }
  return out;
}

}  // namespace truecut::analysis::diagnosis
