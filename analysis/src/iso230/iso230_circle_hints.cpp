#include "iso230_circle_hints.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "truecut/rt/number_format.hpp"

namespace truecut::analysis {
namespace {

// The smallest 2θ or 0θ coefficient worth naming: well above what noise
// gives a Fourier coefficient (σ·√(2/N)), and not a sliver of G.
double threshold_mm(const CircularTest& t) {
  double se = 0;
  for (const auto& r : t.runs)
    if (!r.harmonics.empty()) se = std::max(se, r.noise_mm * std::sqrt(2.0 / double(r.samples)));
  return std::max({5 * se, 1e-4, 0.05 * t.G_mm});
}

}  // namespace

std::vector<CircleHint> circle_hints(const CircularTest& t) {
  std::vector<CircleHint> hints;
  if (t.harmonics.size() < 3) return hints;
  const double thr = threshold_mm(t);
  const double R = t.nominal_radius_mm;
  const std::string& p = t.axis_p;
  const std::string& q = t.axis_q;

  const double a0 = t.harmonics[0].cos_mm;
  if (std::abs(a0) > thr)
    hints.push_back({"radius_offset", "", a0 * 1e3, "um",
                     "mean radius " + rt::format_printf("%.1f µm", std::abs(a0) * 1e3) +
                         (a0 > 0 ? " larger" : " smaller") +
                         " than nominal: ballbar length calibration, or a scale error common to " +
                         p + " and " + q + " of about " + rt::format_printf("%.1f", a0 / R * 1e6) +
                         " µm/m"});

  const double a2 = t.harmonics[2].cos_mm, b2 = t.harmonics[2].sin_mm;
  if (std::abs(a2) > thr)
    hints.push_back({"scale_mismatch", a2 > 0 ? p : q, 2 * a2 / R * 1e6, "um/m",
                     "ellipse along " + p + "/" + q + " (2θ term at " + (a2 > 0 ? "0°" : "90°") +
                         "): " + (a2 > 0 ? p : q) + " travels " +
                         rt::format_printf("%.1f", std::abs(2 * a2 / R) * 1e6) +
                         " µm/m more than " + (a2 > 0 ? q : p) +
                         " (relative scale or pitch error)"});

  const CircleRun* ccw = nullptr;
  const CircleRun* cw = nullptr;
  for (const auto& r : t.runs) {
    if (r.harmonics.size() < 3) continue;
    (r.direction == "ccw" ? ccw : cw) = &r;
  }
  const bool both = ccw && cw;
  if (std::abs(b2) > thr)
    hints.push_back({"squareness", "", 2 * b2 / R * 1e6, "urad",
                     "ellipse along 45°/135° (2θ term at " + std::string(b2 > 0 ? "45°" : "135°") +
                         ") in " + (both ? "both directions" : "the one direction measured") +
                         ": " + p + " and " + q + " out of square by " +
                         rt::format_printf("%.1f", std::abs(2 * b2 / R) * 1e6) +
                         " µrad (angle between +" + p + " and +" + q +
                         (b2 > 0 ? " below" : " above") + " 90°)" +
                         (both ? ""
                               : "; servo mismatch looks the same in one direction, a run in "
                                 "the other direction separates them")});
  if (both) {
    const double flip_a = (ccw->harmonics[2].cos_mm - cw->harmonics[2].cos_mm) / 2;
    const double flip_b = (ccw->harmonics[2].sin_mm - cw->harmonics[2].sin_mm) / 2;
    const double feed = (ccw->feed_mm_per_s + cw->feed_mm_per_s) / 2;
    if (std::hypot(flip_a, flip_b) > thr && feed > 0) {
      const double lag_s = 2 * flip_b / feed;
      hints.push_back({"servo_mismatch", lag_s > 0 ? p : q, std::abs(lag_s) * 1e3, "ms",
                       "45° ellipse that turns over between CW and CCW: " + (lag_s > 0 ? p : q) +
                           " lags " + (lag_s > 0 ? q : p) + " by about " +
                           rt::format_printf("%.2f", std::abs(lag_s) * 1e3) +
                           " ms (servo gain or feed-forward mismatch)"});
    }
  }

  // Reversal features, the largest per axis.
  struct Worst {
    double value = 0;
    std::string where;
  };
  std::map<std::string, Worst> spikes, steps;
  for (const auto& r : t.runs) {
    for (const auto& f : r.reversals) {
      const std::string at = r.direction + " " + rt::format_printf("%.0f", f.angle_deg) + "°";
      // Largest of ~100 noise samples stays below 6σ; an intercept from n
      // samples has a standard error of about 2σ/√n.
      const double spike_floor = std::max(1e-4, 6 * r.residual_sigma_mm);
      const double step_floor =
          std::max(1e-4, 5 * 2 * r.residual_sigma_mm /
                             std::sqrt(double(std::max<std::size_t>(f.samples, 1))));
      if (std::abs(f.spike_mm) > spike_floor && std::abs(f.spike_mm) > 2 * std::abs(f.step_mm)) {
        auto& w = spikes[f.reversing_axis];
        w.where += (w.where.empty() ? "" : ", ") + at;
        w.value = std::max(w.value, std::abs(f.spike_mm));
      } else if (std::abs(f.step_mm) > step_floor) {
        auto& w = steps[f.reversing_axis];
        w.where += (w.where.empty() ? "" : ", ") + at;
        w.value = std::max(w.value, std::abs(f.step_mm));
      }
    }
  }
  for (const auto& [axis, w] : spikes)
    hints.push_back({"reversal_spike", axis, w.value * 1e3, "um",
                     "spikes of up to " + rt::format_printf("%.1f µm", w.value * 1e3) + " where " +
                         axis + " reverses (" + w.where +
                         "): friction / stick-slip at reversal, tune the reversal compensation"});
  for (const auto& [axis, w] : steps)
    hints.push_back({"backlash", axis, w.value * 1e3, "um",
                     "steps of up to " + rt::format_printf("%.1f µm", w.value * 1e3) + " where " +
                         axis + " reverses (" + w.where + "): lost motion (backlash) on " + axis});
  return hints;
}

}  // namespace truecut::analysis
