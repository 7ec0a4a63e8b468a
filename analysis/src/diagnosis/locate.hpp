// The locate stage: noise floor, residual statistics by motion condition,
// time window, program line and rotary angle, and the whiteness check.
#pragma once

#include <vector>

#include "trace.hpp"
#include "truecut/analysis/diagnosis/diagnosis.hpp"

namespace truecut::analysis::diagnosis {

// Robust high-pass estimate: σ = 1.4826 · MAD(Δ²r) / √6 over the samples
// in `use` (the second difference of white noise has variance 6σ²; smooth
// model errors hardly reach it). Falls back to the RMS of Δ²r / √6 when the
// MAD is zero (coarsely quantised data).
double noise_floor(const std::vector<double>& r, const std::vector<char>& use);

// The resolution of a recorded channel: the step q of the grid its values
// lie on (every change between consecutive samples in `use` a whole multiple
// of q, within 2 % of q, and at least three different multiples: equal steps
// are a constant speed), or 0 when there is none (continuous, noisy data).
// A quantised channel carries at least q/√12 of noise, whatever the MAD says:
// a noise-free recording from a simulator, or a slow axis that moves one
// count at a time, has second differences that are mostly exactly zero.
double grid_step(const std::vector<double>& y, const std::vector<char>& use);

// Standard deviation about the window means in standstill windows (at
// least `min_samples` consecutive samples with |v_cmd| below threshold).
std::optional<double> standstill_noise(const std::vector<double>& r, const std::vector<double>& v,
                                       const std::vector<char>& use, double v_threshold,
                                       std::size_t min_samples);

enum class Motion { kStandstill, kReversal, kAcceleration, kConstantVelocity };
const char* motion_name(Motion m);
std::vector<Motion> classify_motion(const std::vector<double>& t, const std::vector<double>& cmd);

// Appends the regions of axis `axis` where the residual is significantly
// above its floor: the noise `floor` and, per sample, the re-simulation's
// own `uncertainty` (empty: none), added in quadrature over the region; and
// above `step`, the recording's resolution (0: continuous).
void locate_axis(const Trace& trace, int joint, const std::vector<double>& residual,
                 const std::vector<char>& use, double floor, double step,
                 const std::vector<double>& uncertainty, std::vector<Mismatch>& out);

// Ljung–Box over lags 1..h of residual series (each a separate axis).
Whiteness whiteness(const std::vector<std::vector<double>>& series, int lags = 10);

}  // namespace truecut::analysis::diagnosis
