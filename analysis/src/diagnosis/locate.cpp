#include "locate.hpp"

#include <algorithm>
#include <boost/math/special_functions/gamma.hpp>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>

#include "truecut/rt/number_format.hpp"

namespace truecut::analysis::diagnosis {

namespace {

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

struct Acc {
  std::size_t n = 0;
  double ss = 0, sum = 0, mx = 0, uu = 0;
  void add(double r, double u) {
    ++n, ss += r * r, sum += r, uu += u * u;
    mx = std::max(mx, std::abs(r));
  }
  void merge(const Acc& o) {
    n += o.n, ss += o.ss, sum += o.sum, uu += o.uu;
    mx = std::max(mx, o.mx);
  }
  double rms() const { return n ? std::sqrt(ss / n) : 0; }
  // The region's floor: the noise and its mean squared re-simulation uncertainty.
  double floor(double noise) const { return std::sqrt(noise * noise + (n ? uu / n : 0.0)); }
};

// Significant: at least 10 samples and an RMS 1.5 times the floor or more
// (for white noise at the floor the RMS of 10 samples exceeds 1.5σ with a
// probability below 0.1 %), and above one step of the recording's grid
// (below that, rounding flips between recording and model are all it shows).
bool significant(const Acc& a, double noise, double step) {
  return a.n >= 10 && a.rms() > 1.5 * a.floor(noise) && a.rms() > step;
}

Mismatch make(const std::string& axis, const std::string& where, const std::string& what,
              const Acc& a, double floor) {
  Mismatch m;
  m.axis = axis;
  m.where = where;
  m.what = what;
  m.samples = a.n;
  m.rms_mm = a.rms();
  m.max_mm = a.mx;
  m.mean_mm = a.n ? a.sum / a.n : 0;
  m.ratio_to_floor = a.floor(floor) > 0 ? a.rms() / a.floor(floor) : INFINITY;
  return m;
}

}  // namespace

double noise_floor(const std::vector<double>& r, const std::vector<char>& use) {
  std::vector<double> d2;
  for (std::size_t k = 1; k + 1 < r.size(); ++k)
    if (use[k - 1] && use[k] && use[k + 1]) d2.push_back(r[k + 1] - 2 * r[k] + r[k - 1]);
  if (d2.empty()) return 0.0;
  const double med = median(d2);
  std::vector<double> dev(d2.size());
  for (std::size_t i = 0; i < d2.size(); ++i)
    dev[i] = std::abs(d2[i] - med);
  const double mad = median(dev);
  if (mad > 0) return 1.4826 * mad / std::sqrt(6.0);
  double ss = 0;
  for (double v : d2)
    ss += v * v;
  return std::sqrt(ss / d2.size() / 6.0);
}

double grid_step(const std::vector<double>& y, const std::vector<char>& use) {
  double scale = 0;
  for (std::size_t k = 0; k < y.size(); ++k)
    if (use[k]) scale = std::max(scale, std::abs(y[k]));
  const double tiny = 1e-9 * std::max(1.0, scale);  // below: decimal-to-binary rounding
  std::vector<double> steps;
  for (std::size_t k = 1; k < y.size(); ++k)
    if (use[k] && use[k - 1]) {
      const double d = std::abs(y[k] - y[k - 1]);
      if (d > tiny) steps.push_back(d);
    }
  if (steps.size() < 10) return 0.0;
  const double smallest = *std::min_element(steps.begin(), steps.end());
  // The smallest change may itself be a few counts: try its divisors.
  for (int divisor : {1, 2, 3, 4, 5, 10}) {
    const double q = smallest / divisor;
    if (q <= 2 * tiny) break;
    std::size_t off_grid = 0;
    std::set<double> multiples;
    for (double d : steps) {
      const double m = d / q;
      if (m > 1e6 || std::abs(m - std::round(m)) > 0.02)
        ++off_grid;
      else if (multiples.size() < 3)
        multiples.insert(std::round(m));
    }
    // Steps of one size only are a constant speed, not a grid.
    if (off_grid <= steps.size() / 200 && multiples.size() >= 3) return q;
  }
  return 0.0;
}

std::optional<double> standstill_noise(const std::vector<double>& r, const std::vector<double>& v,
                                       const std::vector<char>& use, double v_threshold,
                                       std::size_t min_samples) {
  double ss = 0;
  std::size_t n = 0, windows = 0;
  std::size_t k = 0;
  while (k < r.size()) {
    if (!(use[k] && std::abs(v[k]) < v_threshold)) {
      ++k;
      continue;
    }
    std::size_t e = k;
    while (e < r.size() && use[e] && std::abs(v[e]) < v_threshold)
      ++e;
    // Skip the first half of the window: the servo may still settle.
    const std::size_t b = k + (e - k) / 2;
    if (e - b >= min_samples) {
      double mean = 0;
      for (std::size_t i = b; i < e; ++i)
        mean += r[i];
      mean /= double(e - b);
      for (std::size_t i = b; i < e; ++i)
        ss += (r[i] - mean) * (r[i] - mean);
      n += e - b - 1;
      ++windows;
    }
    k = e;
  }
  if (windows == 0 || n == 0) return std::nullopt;
  return std::sqrt(ss / double(n));
}

const char* motion_name(Motion m) {
  switch (m) {
    case Motion::kStandstill:
      return "standstill";
    case Motion::kReversal:
      return "reversal";
    case Motion::kAcceleration:
      return "acceleration";
    default:
      return "constant_velocity";
  }
}

std::vector<Motion> classify_motion(const std::vector<double>& t, const std::vector<double>& cmd) {
  const auto v = derivative(t, cmd);
  const auto a = derivative(t, v);
  const std::size_t n = t.size();
  double vmax = 0, amax = 0;
  for (std::size_t k = 0; k < n; ++k)
    vmax = std::max(vmax, std::abs(v[k])), amax = std::max(amax, std::abs(a[k]));
  const double v_thr = std::max(1e-3 * vmax, 1e-9), a_thr = 0.05 * amax;
  std::vector<Motion> m(n, Motion::kConstantVelocity);
  for (std::size_t k = 0; k < n; ++k) {
    if (std::abs(v[k]) < v_thr)
      m[k] = Motion::kStandstill;
    else if (std::abs(a[k]) > a_thr)
      m[k] = Motion::kAcceleration;
  }
  // Reversal: from 50 ms (at least 2 samples) before to 100 ms after the
  // velocity changes sign (a standstill in between counts when it is short).
  const double dt = n > 1 ? (t.back() - t.front()) / double(n - 1) : 1;
  const std::size_t before = std::max<std::size_t>(2, std::size_t(0.05 / dt));
  const std::size_t after = std::max<std::size_t>(3, std::size_t(0.1 / dt));
  int last_sign = 0;
  std::size_t last_moving = 0;
  for (std::size_t k = 0; k < n; ++k) {
    if (std::abs(v[k]) < v_thr) continue;
    const int s = v[k] > 0 ? 1 : -1;
    if (last_sign != 0 && s != last_sign && k - last_moving <= 2 * after) {
      const std::size_t lo = last_moving >= before ? last_moving - before : 0;
      for (std::size_t i = lo; i < std::min(n, k + after); ++i)
        m[i] = Motion::kReversal;
    }
    last_sign = s;
    last_moving = k;
  }
  return m;
}

void locate_axis(const Trace& tr, int j, const std::vector<double>& r, const std::vector<char>& use,
                 double floor, double step, const std::vector<double>& uncertainty,
                 std::vector<Mismatch>& out) {
  const std::string ax(sim::kJointNames[j]);
  auto u = [&](std::size_t k) { return uncertainty.empty() ? 0.0 : uncertainty[k]; };
  const auto motion = classify_motion(tr.t_s, tr.cmd[j]);
  Acc whole, by_motion[4];
  for (std::size_t k = 0; k < r.size(); ++k) {
    if (!use[k]) continue;
    whole.add(r[k], u(k));
    by_motion[int(motion[k])].add(r[k], u(k));
  }
  if (significant(whole, floor, step))
    out.push_back(make(ax, "axis", "whole recording", whole, floor));
  for (int m = 0; m < 4; ++m)
    if (significant(by_motion[m], floor, step))
      out.push_back(make(ax, "condition", motion_name(Motion(m)), by_motion[m], floor));

  // Time windows: 20 equal windows, neighbours above the floor merged.
  const double t0 = tr.t_s.front(), t1 = tr.t_s.back();
  const int W = 20;
  std::vector<Acc> win(W);
  for (std::size_t k = 0; k < r.size(); ++k)
    if (use[k]) win[std::min(W - 1, int((tr.t_s[k] - t0) / (t1 - t0 + 1e-12) * W))].add(r[k], u(k));
  for (int w = 0; w < W;) {
    if (!significant(win[w], floor, step)) {
      ++w;
      continue;
    }
    Acc merged;
    int e = w;
    for (; e < W && significant(win[e], floor, step); ++e)
      merged.merge(win[e]);
    out.push_back(
        make(ax, "time",
             rt::format_printf("t %.3f–%.3f s", t0 + (t1 - t0) * w / W, t0 + (t1 - t0) * e / W),
             merged, floor));
    w = e;
  }
  if (!tr.line.empty()) {
    std::map<double, Acc> lines;
    for (std::size_t k = 0; k < r.size(); ++k)
      if (use[k]) lines[tr.line[k]].add(r[k], u(k));
    std::vector<Mismatch> ms;
    for (const auto& [l, a] : lines)
      if (significant(a, floor, step))
        ms.push_back(make(ax, "line", rt::format_printf("line %.0f", l), a, floor));
    std::sort(ms.begin(), ms.end(),
              [](const Mismatch& a, const Mismatch& b) { return a.rms_mm > b.rms_mm; });
    if (ms.size() > 10) ms.resize(10);
    out.insert(out.end(), ms.begin(), ms.end());
  }
  for (int rj : {int(sim::kA), int(sim::kC)}) {
    if (tr.cmd[rj].empty()) continue;
    Acc bins[12];
    for (std::size_t k = 0; k < r.size(); ++k) {
      if (!use[k]) continue;
      double ang = std::fmod(tr.cmd[rj][k], 360.0);
      if (ang < 0) ang += 360;
      bins[std::min(11, int(ang / 30))].add(r[k], u(k));
    }
    for (int b = 0; b < 12; ++b)
      if (significant(bins[b], floor, step))
        out.push_back(make(ax, "rotary_angle",
                           std::string(sim::kJointNames[rj]) +
                               rt::format_printf(" %.0f–%.0f deg", b * 30.0, b * 30.0 + 30),
                           bins[b], floor));
  }
}

Whiteness whiteness(const std::vector<std::vector<double>>& series, int lags) {
  Whiteness w;
  w.lags = lags;
  double den = 0;
  std::size_t n = 0;
  std::vector<double> num(std::size_t(lags) + 1, 0.0);
  for (const auto& s : series) {
    double mean = 0;
    for (double v : s)
      mean += v;
    mean /= std::max<std::size_t>(1, s.size());
    for (std::size_t k = 0; k < s.size(); ++k) {
      den += (s[k] - mean) * (s[k] - mean);
      for (int l = 1; l <= lags && std::size_t(l) <= k; ++l)
        num[std::size_t(l)] += (s[k] - mean) * (s[k - std::size_t(l)] - mean);
    }
    n += s.size();
  }
  if (den <= 0 || n <= std::size_t(lags) + 1) return w;
  double q = 0;
  for (int l = 1; l <= lags; ++l) {
    const double r = num[std::size_t(l)] / den;
    w.autocorrelation.push_back(r);
    q += r * r / double(n - std::size_t(l));
  }
  w.ljung_box_q = double(n) * double(n + 2) * q;
  w.p_value = boost::math::gamma_q(lags / 2.0, w.ljung_box_q / 2.0);
  w.white = w.p_value >= 0.01;
  return w;
}

}  // namespace truecut::analysis::diagnosis
