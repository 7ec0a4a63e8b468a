// ISO 230-4 circular test: runs, G, H, F and harmonics (docs/iso230.md).
#include "truecut/analysis/iso230_circular.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "circle_fit.hpp"
#include "iso230_circle_hints.hpp"

namespace truecut::analysis {
namespace {

constexpr double kDeg = 180.0 / std::numbers::pi;

double wrap_pi(double a) {  // → (−π, π]
  a = std::remainder(a, 2 * std::numbers::pi);
  return a <= -std::numbers::pi ? a + 2 * std::numbers::pi : a;
}

struct Nominal {
  detail::CircleFit fit;
  std::vector<std::size_t> on_circle;
};

Nominal nominal_circle(const std::vector<double>& p, const std::vector<double>& q,
                       const CircleOptions& o) {
  Nominal n;
  n.fit = detail::fit_circle(p, q);
  for (double tol : {0.2, 0.05, o.on_circle_tolerance}) {
    if (!n.fit.ok) return n;
    const double r = o.radius_mm.value_or(n.fit.r);
    n.on_circle.clear();
    for (std::size_t i = 0; i < p.size(); ++i)
      if (std::abs(std::hypot(p[i] - n.fit.cp, q[i] - n.fit.cq) - r) <= tol * r)
        n.on_circle.push_back(i);
    n.fit = detail::fit_circle(p, q, n.on_circle);
  }
  return n;
}

// Value at 0 of the least-squares line through (x, y).
double intercept(const std::vector<double>& x, const std::vector<double>& y) {
  const double n = double(x.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < x.size(); ++i)
    sx += x[i], sy += y[i], sxx += x[i] * x[i], sxy += x[i] * y[i];
  const double det = n * sxx - sx * sx;
  return std::abs(det) < 1e-12 ? sy / n : (sy * sxx - sx * sxy) / det;
}

// At each crossing the step is the jump between straight lines fitted to
// the 15° before and after (smooth shapes extrapolate across it; a lost
// motion does not); the spike is the largest excursion in the 10° after.
std::vector<ReversalFeature> reversal_features(const std::vector<double>& theta,
                                               const std::vector<double>& e, int travel,
                                               const std::string& p, const std::string& q) {
  std::vector<ReversalFeature> out;
  for (int quadrant = 0; quadrant < 4; ++quadrant) {
    const double at = quadrant * std::numbers::pi / 2;
    double spike = 0;
    std::vector<double> xa, ya, xb, yb;
    for (std::size_t i = 0; i < theta.size(); ++i) {
      const double d = travel * wrap_pi(theta[i] - at) * kDeg;  // degrees past the crossing
      if (d > 0 && d <= 10 && std::abs(e[i]) > std::abs(spike)) spike = e[i];
      if (d > 0 && d <= 15) xa.push_back(d), ya.push_back(e[i]);
      if (d < 0 && d >= -15) xb.push_back(d), yb.push_back(e[i]);
    }
    if (xa.size() < 3 || xb.size() < 3) continue;
    ReversalFeature f;
    f.angle_deg = quadrant * 90.0;
    f.reversing_axis = quadrant % 2 == 0 ? p : q;  // p stops at 0°/180°, q at 90°/270°
    f.spike_mm = spike;
    f.step_mm = intercept(xa, ya) - intercept(xb, yb);
    f.samples = std::min(xa.size(), xb.size());
    out.push_back(f);
  }
  return out;
}

CircleRun evaluate_run(const std::string& direction, const std::vector<std::size_t>& idx,
                       const std::vector<double>& mp, const std::vector<double>& mq, double radius,
                       double swept_rad, double feed, const CircleOptions& o) {
  CircleRun run;
  run.direction = direction;
  run.samples = idx.size();
  run.swept_deg = swept_rad * kDeg;
  run.feed_mm_per_s = feed;
  const auto fit = detail::fit_circle(mp, mq, idx);
  run.centre_p_mm = fit.cp;
  run.centre_q_mm = fit.cq;
  run.fitted_radius_mm = fit.r;
  std::vector<double> theta, dr;
  for (auto i : idx) {
    theta.push_back(std::atan2(mq[i] - fit.cq, mp[i] - fit.cp));
    dr.push_back(std::hypot(mp[i] - fit.cp, mq[i] - fit.cq) - radius);
  }
  const auto [lo, hi] = std::minmax_element(dr.begin(), dr.end());
  run.F_min_mm = *lo;
  run.F_max_mm = *hi;
  run.G_mm = *hi - *lo;
  if (run.swept_deg >= 300) {
    const auto c = detail::fit_fourier(theta, dr, o.harmonics);
    if (!c.empty()) {
      for (int k = 0; k <= o.harmonics; ++k) {
        Harmonic h;
        h.order = k;
        h.cos_mm = c[2 * k];
        h.sin_mm = c[2 * k + 1];
        h.amplitude_mm = k == 0 ? h.cos_mm : std::hypot(h.cos_mm, h.sin_mm);
        h.phase_deg = k == 0 ? 0 : std::atan2(h.sin_mm, h.cos_mm) * kDeg / k;
        if (h.phase_deg < 0) h.phase_deg += 360.0 / std::max(k, 1);
        run.harmonics.push_back(h);
      }
      double ss = 0;
      std::vector<double> e(dr.size());
      for (std::size_t i = 0; i < dr.size(); ++i) {
        const double r = dr[i] - detail::eval_fourier(c, theta[i], o.harmonics);
        ss += r * r;
        e[i] = dr[i] - detail::eval_fourier(c, theta[i], 2);
      }
      run.noise_mm = std::sqrt(ss / double(dr.size()));
      run.reversals = reversal_features(theta, e, direction == "ccw" ? 1 : -1, o.axis_p, o.axis_q);
      // Noise from neighbour differences: the shape barely changes between
      // samples, so this is the floor a feature must stand out of.
      std::vector<double> dev;
      for (std::size_t i = 1; i < e.size(); ++i)
        dev.push_back((e[i] - e[i - 1]) / std::sqrt(2.0));
      std::nth_element(dev.begin(), dev.begin() + dev.size() / 2, dev.end());
      const double median = dev[dev.size() / 2];
      for (auto& x : dev)
        x = std::abs(x - median);
      std::nth_element(dev.begin(), dev.begin() + dev.size() / 2, dev.end());
      run.residual_sigma_mm = 1.4826 * dev[dev.size() / 2];
    }
  }
  const std::size_t stride = std::max<std::size_t>(1, (theta.size() + 719) / 720);
  for (std::size_t i = 0; i < theta.size(); i += stride) {
    double deg = theta[i] * kDeg;
    run.angle_deg.push_back(deg < 0 ? deg + 360 : deg);
    run.deviation_mm.push_back(dr[i]);
  }
  return run;
}

// H: radial difference of the two directions at equal angles about one
// common centre; the CCW path is interpolated at each CW sample's angle.
std::optional<double> hysteresis(const std::vector<std::size_t>& ccw,
                                 const std::vector<std::size_t>& cw, const std::vector<double>& mp,
                                 const std::vector<double>& mq) {
  std::vector<std::size_t> both = ccw;
  both.insert(both.end(), cw.begin(), cw.end());
  const auto fit = detail::fit_circle(mp, mq, both);
  if (!fit.ok) return std::nullopt;
  auto polar = [&](std::size_t i) {
    return std::pair{std::atan2(mq[i] - fit.cq, mp[i] - fit.cp),
                     std::hypot(mp[i] - fit.cp, mq[i] - fit.cq)};
  };
  std::vector<std::pair<double, double>> ref;
  for (auto i : ccw)
    ref.push_back(polar(i));
  std::sort(ref.begin(), ref.end());
  const double max_gap = 5 / kDeg;
  std::optional<double> h;
  for (auto i : cw) {
    const auto [th, r] = polar(i);
    auto hi = std::lower_bound(ref.begin(), ref.end(), std::pair<double, double>{th, -HUGE_VAL});
    const auto& b = hi == ref.end() ? ref.front() : *hi;
    const auto& a = hi == ref.begin() ? ref.back() : *(hi - 1);
    const double span = wrap_pi(b.first - a.first) == 0 ? 0 : std::abs(wrap_pi(b.first - a.first));
    if (span > max_gap) continue;
    const double w = span == 0 ? 0 : std::abs(wrap_pi(th - a.first)) / span;
    const double r_ccw = a.second + w * (b.second - a.second);
    h = std::max(h.value_or(0.0), std::abs(r_ccw - r));
  }
  return h;
}

}  // namespace

CircularTest evaluate_circle(const Recording& rec, const CircleOptions& o) {
  CircularTest out;
  out.axis_p = o.axis_p;
  out.axis_q = o.axis_q;
  const auto& pc = rec.channel(o.axis_p + "_cmd");
  const auto& qc = rec.channel(o.axis_q + "_cmd");
  const auto* mp = rec.measured(o.axis_p);
  const auto* mq = rec.measured(o.axis_q);
  if (!mp) rec.channel(o.axis_p + "_act");
  if (!mq) rec.channel(o.axis_q + "_act");
  out.measured_p = rec.has(o.axis_p + "_meas") ? o.axis_p + "_meas" : o.axis_p + "_act";
  out.measured_q = rec.has(o.axis_q + "_meas") ? o.axis_q + "_meas" : o.axis_q + "_act";

  const auto nominal = nominal_circle(pc, qc, o);
  if (!nominal.fit.ok || nominal.on_circle.size() < 8)
    throw RecordingError(
        rec.file + ": no circle found in " + o.axis_p + "_cmd/" + o.axis_q + "_cmd" +
        (o.radius_mm ? " with radius " + std::to_string(*o.radius_mm) + " mm" : ""));
  out.nominal_centre_p_mm = nominal.fit.cp;
  out.nominal_centre_q_mm = nominal.fit.cq;
  out.nominal_radius_mm = o.radius_mm.value_or(nominal.fit.r);
  if (o.radius_mm && std::abs(*o.radius_mm - nominal.fit.r) > 1e-3)
    out.notes.push_back("the commanded circle's radius is " + std::to_string(nominal.fit.r) +
                        " mm, --radius says " + std::to_string(*o.radius_mm) + " mm");

  // Split the on-circle samples by the sense of the commanded motion.
  std::vector<std::size_t> idx[2];  // 0 ccw, 1 cw
  double swept[2] = {0, 0}, path_mm[2] = {0, 0}, time_s[2] = {0, 0};
  const auto& on = nominal.on_circle;
  for (std::size_t k = 1; k < on.size(); ++k) {
    const std::size_t i = on[k], j = on[k - 1];
    if (i != j + 1) continue;
    const double a0 = std::atan2(qc[j] - nominal.fit.cq, pc[j] - nominal.fit.cp);
    const double a1 = std::atan2(qc[i] - nominal.fit.cq, pc[i] - nominal.fit.cp);
    const double d = wrap_pi(a1 - a0);
    if (std::abs(d) < 1e-9) continue;
    const int s = d > 0 ? 0 : 1;
    idx[s].push_back(i);
    swept[s] += std::abs(d);
    path_mm[s] += std::abs(d) * nominal.fit.r;
    time_s[s] += rec.t_s[i] - rec.t_s[j];
  }
  const char* names[2] = {"ccw", "cw"};
  for (int s = 0; s < 2; ++s) {
    if (idx[s].size() < 8 || swept[s] < 20 / kDeg) continue;
    auto run = evaluate_run(names[s], idx[s], *mp, *mq, out.nominal_radius_mm, swept[s],
                            path_mm[s] / time_s[s], o);
    out.runs.push_back(std::move(run));
  }
  if (out.runs.empty())
    throw RecordingError(rec.file + ": the circle in " + o.axis_p + "_cmd/" + o.axis_q +
                         "_cmd has no run of at least 20° in one direction");

  out.F_max_mm = -INFINITY;
  out.F_min_mm = INFINITY;
  for (const auto& r : out.runs) {
    out.G_mm = std::max(out.G_mm, r.G_mm);
    out.F_max_mm = std::max(out.F_max_mm, r.F_max_mm);
    out.F_min_mm = std::min(out.F_min_mm, r.F_min_mm);
    if (r.swept_deg < 360)
      out.notes.push_back(std::string(r.direction) + " run covers " +
                          std::to_string(int(r.swept_deg)) + "°, less than a full circle");
  }
  out.F_mm = std::max(std::abs(out.F_max_mm), std::abs(out.F_min_mm));
  if (out.runs.size() == 2) out.H_mm = hysteresis(idx[0], idx[1], *mp, *mq);

  std::vector<const CircleRun*> with_harmonics;
  for (const auto& r : out.runs)
    if (!r.harmonics.empty()) with_harmonics.push_back(&r);
  if (!with_harmonics.empty()) {
    out.harmonics = with_harmonics[0]->harmonics;
    for (auto& h : out.harmonics) {
      h.cos_mm = h.sin_mm = 0;
      for (const auto* r : with_harmonics) {
        h.cos_mm += r->harmonics[h.order].cos_mm / double(with_harmonics.size());
        h.sin_mm += r->harmonics[h.order].sin_mm / double(with_harmonics.size());
      }
      h.amplitude_mm = h.order == 0 ? h.cos_mm : std::hypot(h.cos_mm, h.sin_mm);
      h.phase_deg = h.order == 0 ? 0 : std::atan2(h.sin_mm, h.cos_mm) * kDeg / h.order;
      if (h.phase_deg < 0) h.phase_deg += 360.0 / std::max(h.order, 1);
    }
  } else {
    out.notes.push_back(
        "no run covers 300°: harmonics and interpretation hints need a full circle");
  }
  out.hints = circle_hints(out);
  return out;
}

}  // namespace truecut::analysis
