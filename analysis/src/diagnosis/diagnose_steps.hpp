// Steps of the trace-mode pipeline (diagnose.cpp) that stand on their own:
// which samples enter the fit, how uncertain the re-simulation is between
// coarse samples, the noise floors and the logging-delay search.
#pragma once

#include <array>
#include <vector>

#include "trace.hpp"
#include "truecut/analysis/diagnosis/diagnosis.hpp"

namespace truecut::analysis::diagnosis {

struct Masks {
  std::vector<char> train, heldout, valid;  // valid: inside the delay margins, no glitch
  std::size_t excluded = 0;                 // glitch samples
};

// Samples within `margin_s` of either end, and those around recorder
// glitches (isolated command jumps), are left out; of the others the last
// `holdout_fraction` of the time is held out, the rest trains.
Masks make_masks(const Trace& tr, double margin_s, double holdout_fraction);

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
