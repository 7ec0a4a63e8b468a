// Steps of the trace-mode pipeline (diagnose.cpp) that stand on their own:
// which samples enter the fit, how uncertain the re-simulation is between
// coarse samples, the noise floors and the logging-delay search.
#pragma once

#include <array>
#include <vector>

#include "trace.hpp"
#include "truecut/analysis/diagnosis/diagnosis.hpp"

namespace truecut::analysis::diagnosis {

// Glitch rows of one recorded series: samples k far off both one-sided
// predictions of their neighbours. With the left prediction
// pL = y[k-1] + (y[k-1] − y[k-2])·(t[k] − t[k-1])/(t[k-1] − t[k-2]) and the
// right one pR likewise from k+1, k+2, sample k is a glitch when y[k] − pL
// and y[k] − pR have the same sign and both exceed `factor` times the local
// scale s = max(|y[k-1] − y[k-2]|, |y[k+2] − y[k+1]|, |y[k+1] − y[k-1]|,
// the median |step| within ±10 rows, the recorded resolution at y[k±1]);
// the resolution is the smallest non-zero step between consecutive samples
// of the same decade (3 significant digits: 1 mm above 100 mm, 0.1 below).
// A reversal (the one-sided predictions bracket it), a step (|y[k+1] −
// y[k-1]| is the step) and a fast move (its own steps set the scale) are not
// glitches; two or more consecutive samples off are not isolated and not
// flagged. Rows 0, 1 and the last two are never flagged.
struct Glitch {
  std::size_t row = 0;
  double deviation = 0;  // min(|y − pL|, |y − pR|)
};
std::vector<Glitch> isolated_glitches(const std::vector<double>& t, const std::vector<double>& y,
                                      double factor = 8.0);

struct Masks {
  std::vector<char> train, heldout, valid;  // valid: inside the delay margins, no glitch
  std::size_t excluded = 0;                 // glitch samples
  std::vector<GlitchRow> glitch_rows;       // isolated_glitches of every cmd and target
};

// Samples within `margin_s` of either end, those around recorder glitches
// (isolated command jumps) and glitch rows (isolated_glitches of any
// command or target) are left out; of the others the last
// `holdout_fraction` of the time is held out, the rest trains.
Masks make_masks(const Trace& tr, double margin_s, double holdout_fraction);

// Commands of the glitch rows replaced by the straight line between their
// neighbours (so that the re-simulation does not drive the axis into the
// glitch); the samples stay excluded by the masks.
void repair_command_glitches(Trace& tr, const std::vector<GlitchRow>& glitches);

// Per axis of tr.axes, per row: the factor on the axis' weight (empty: 1).
using SampleWeights = std::vector<std::vector<double>>;

// Weighted, centred RSS of the recording read at t + d against a fixed simulation.
double delay_rss(const Trace& tr, const Simulated& sim, const std::vector<char>& use,
                 const std::vector<double>& w, const SampleWeights& sw, double d);
// The delay minimising delay_rss in [lo, hi]: a grid, then golden section.
double best_delay(const Trace& tr, const Simulated& sim, const std::vector<char>& use,
                  const std::vector<double>& w, const SampleWeights& sw, double lo, double hi,
                  double step);

// The re-simulation's own error between coarse samples (all zero / empty
// when every interval is one servo period): per joint its RMS over the
// training samples and its size per sample.
struct InterpolationError {
  std::array<double, sim::kJointCount> rms{};
  std::array<std::vector<double>, sim::kJointCount> u;  // per sample; empty: none
};
InterpolationError interpolation_error(const Trace& tr, const Simulated& sim0,
                                       const std::vector<char>& train,
                                       const sim::MachineParams& base, double max_period_s);

// Per axis of tr.axes: the noise floor, the fit's weights and per-sample
// weights, from the unaligned residual tr.target − sim0.target.
struct NoiseFloors {
  std::array<double, sim::kJointCount> noise_only{};  // without the interpolation error
  std::vector<AxisStats> axes;  // axis, target, resolution, interpolation, noise floor
  std::vector<double> w;        // per axis of tr.axes
  SampleWeights sw;
};
NoiseFloors estimate_noise_floors(const Trace& tr, const Simulated& sim0,
                                  const std::vector<char>& train, const sim::MachineParams& base,
                                  const InterpolationError& interp);

}  // namespace truecut::analysis::diagnosis
