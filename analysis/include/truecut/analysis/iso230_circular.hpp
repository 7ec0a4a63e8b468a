// ISO 230-4:2022 circular test of two axes from a recording: circular
// deviation G, circular hysteresis H, radial deviation F, plus the Fourier
// components of the radial deviation and ballbar-style readings of them
// (docs/iso230.md). Lengths are in mm (the axes' unit), angles in degrees.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "truecut/analysis/recording.hpp"

namespace truecut::analysis {

struct CircleOptions {
  std::string axis_p = "x", axis_q = "y";  // CCW = from +p towards +q
  std::optional<double> radius_mm;         // nominal radius; default: fitted to <p/q>_cmd
  double on_circle_tolerance = 0.005;      // |r_cmd − R| ≤ this × R counts as on the circle
  int harmonics = 8;                       // highest order fitted
};

// dr(θ) ≈ amplitude·cos(order·(θ − phase)): phase is the first angle of maximum.
struct Harmonic {
  int order = 0;
  double amplitude_mm = 0;
  double phase_deg = 0;
  double cos_mm = 0, sin_mm = 0;  // a_k, b_k of a_k cos kθ + b_k sin kθ
};

// Peak and step of the radial deviation just after an axis reverses (the
// path crosses 0°, 90°, 180°, 270°), beyond the 0..2θ shape.
struct ReversalFeature {
  double angle_deg = 0;
  std::string reversing_axis;
  double spike_mm = 0;      // largest excursion in the 10° after the crossing
  double step_mm = 0;       // jump between lines fitted to the 15° before and after
  std::size_t samples = 0;  // fewest samples on one side
};

struct CircleRun {
  std::string direction;  // "ccw" or "cw"
  std::size_t samples = 0;
  double swept_deg = 0;
  double centre_p_mm = 0, centre_q_mm = 0;  // least-squares centre of the measured path
  double fitted_radius_mm = 0;
  double G_mm = 0;                    // max − min radius about the LSQ centre
  double F_max_mm = 0, F_min_mm = 0;  // max / min of r − R_nominal about the LSQ centre
  double feed_mm_per_s = 0;           // mean commanded path speed
  double noise_mm = 0;                // RMS left after the harmonic fit
  double residual_sigma_mm = 0;       // robust σ of the sample-to-sample noise
  std::vector<Harmonic> harmonics;    // orders 0..K; empty when less than 300° is covered
  std::vector<ReversalFeature> reversals;
  std::vector<double> angle_deg, deviation_mm;  // the path for plots, ≤ 720 points
};

struct CircleHint {
  std::string effect;  // squareness, scale_mismatch, servo_mismatch, radius_offset, reversal_spike,
                       // backlash
  std::string axis;    // where it applies, else empty
  double value = 0;
  std::string unit;
  std::string text;
};

struct CircularTest {
  std::string axis_p, axis_q;
  std::string measured_p, measured_q;  // channels used
  double nominal_centre_p_mm = 0, nominal_centre_q_mm = 0, nominal_radius_mm = 0;
  std::vector<CircleRun> runs;  // at most one per direction
  double G_mm = 0;
  std::optional<double> H_mm;                   // both directions present
  double F_max_mm = 0, F_min_mm = 0, F_mm = 0;  // F_mm: the larger magnitude of the two
  std::vector<Harmonic> harmonics;              // mean of the directions
  std::vector<CircleHint> hints;
  std::vector<std::string> notes;
};

// Throws RecordingError when the channels are missing or no circle is found.
CircularTest evaluate_circle(const Recording& recording, const CircleOptions& options);

}  // namespace truecut::analysis
