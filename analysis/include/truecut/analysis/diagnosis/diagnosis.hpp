// Trace-mode diagnosis (issue 9, docs/diagnosis.md): a recording is compared
// with a re-simulation of its own commands through the believed machine
// model; the logging delay is estimated and removed, the residual located
// (by axis, motion condition, time window, program line, rotary angle),
// explained by a sparse selection of the machine model's named effects
// (BIC over re-simulated signatures), fitted by re-simulation, and the fit
// proven on held-out data.
#pragma once

#include <array>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "truecut/analysis/recording.hpp"
#include "truecut/sim/machine_description.hpp"

namespace truecut::analysis::diagnosis {

struct DiagnosisOptions {
  // Fraction of the recording (its last time block) held out when no
  // hold-out recording is given; 0 disables the split.
  double holdout_fraction = 0.3;
  // Longest simulated servo period: a recording interval dt is simulated in
  // ceil(dt / max_servo_period_s) equal sub-steps, the command interpolated
  // between the recorded samples (see CommandInterpolation).
  double max_servo_period_s = 1e-3;
  // How the command moves between two recorded samples when a recorded
  // interval spans several servo periods. Cubic: a cubic Hermite curve
  // through the samples with three-point slopes (exact for the constant
  // accelerations of a planner's trapezoid; a reversal may turn between
  // samples), zero slope next to a standstill and no overshoot on monotone
  // stretches (so a start from standstill is no reversal). Linear: straight
  // lines (a controller that interpolates its own coarse command linearly).
  enum class CommandInterpolation { kCubic, kLinear };
  CommandInterpolation command_interpolation = CommandInterpolation::kCubic;
  // Largest logging delay searched, s (0: automatic, 10 samples or 50 ms).
  double max_delay_s = 0.0;
  // Minimum BIC improvement for an effect to be selected.
  double bic_threshold = 10.0;
  // An effect is selected only when its contribution (RMS over the fitted
  // block, in units of the noise floor) reaches this: with many samples the
  // BIC alone takes tiny departures of the noise from white Gaussian noise
  // (quantisation, colour) for physics.
  double min_effect_ratio = 0.1;
  // With a tool-centre-point measurement (tcp_true_x/y/z): true when it is
  // taken against a datum fixed in the workpiece frame (absolute); false
  // (default) when its constant offset is unknown (a tracker's or a test
  // ball's registration) and profiled out — then a tool-length error and
  // the A axis line's Z offset move the TCP alike and cannot be told apart.
  bool tcp_datum_known = false;
  // Nominal tool lengths by tool number (the tool table's Z), for the TCP
  // comparison: a sample's `tool` channel picks its length (one tool and no
  // channel: that tool). Empty, or a tool not listed: the description's
  // kinematics.tool.
  std::map<int, double> tool_length_mm;
  std::function<void(const std::string&)> progress;  // lines for stderr; may be empty
};

// A place where the residual is significantly above the noise floor.
struct Mismatch {
  std::string axis;
  std::string where;  // "condition", "time", "line", "rotary_angle", "axis"
  std::string what;   // e.g. "reversal", "t 3.2–4.1 s", "line 42", "c 90–120 deg"
  std::size_t samples = 0;
  double rms_mm = 0.0;
  double max_mm = 0.0;
  double mean_mm = 0.0;
  double ratio_to_floor = 0.0;
};

struct Parameter {
  std::string name;  // machine-description key
  double value = 0.0;
  double ci95_lo = 0.0;
  double ci95_hi = 0.0;
  bool fixed = false;  // held at its start value (not identifiable or a scanned variant)
};

struct Explanation {
  std::string effect;  // machine-description effect name
  std::string axis;    // joint or plane ("xy"), empty for global effects
  std::vector<Parameter> parameters;
  // Shape parameters (a thermal time constant, a pitch period) fitted but
  // not claimed: three of their standard errors exceed ±15 % of the value
  // (the fitted description carries the estimate).
  std::vector<Parameter> undetermined;
  double delta_bic = 0.0;      // BIC gain when the effect was selected (negative = better)
  double rms_effect_mm = 0.0;  // RMS of the effect's signature over the fitted data
  std::string note;
};

struct NotIdentifiable {
  std::string first;  // "effect[:axis]"
  std::string second;
  double correlation = 0.0;
  std::string separate_by;  // what motion or measurement would tell them apart
};

// An effect the fitted data selected but the held-out data do not support:
// left out of the fitted description.
struct NotConfirmed {
  std::string effect;
  std::string axis;
  double heldout_rms_with_mm = 0.0;     // held-out RMS with the effect fitted
  double heldout_rms_without_mm = 0.0;  // and without it
};

struct AxisStats {
  std::string axis;
  std::string target;  // channel compared: <j>_meas or <j>_act
  std::size_t samples = 0;
  double rms_mm = 0.0, max_mm = 0.0, mean_mm = 0.0;
  // The floor mismatches and effects are judged against: the noise (robust
  // high-pass MAD estimate, at least the resolution's q/√12) and the
  // interpolation uncertainty, added in quadrature.
  double noise_floor_mm = 0.0;
  double resolution_mm = 0.0;     // grid step of the recorded target; 0: continuous
  double interpolation_mm = 0.0;  // RMS re-simulation uncertainty between coarse samples
  std::optional<double> standstill_noise_mm;  // std in standstill windows, when any
  double offset_mm = 0.0;                     // constant removed in the alignment
};

struct FitFigures {
  std::size_t samples = 0;
  double rms_before_mm = 0.0, rms_after_mm = 0.0;
  double rms_unaligned_mm = 0.0;  // believed model without removing the logging delay
  double max_before_mm = 0.0, max_after_mm = 0.0;
  std::map<std::string, std::pair<double, double>> per_axis_rms_mm;  // before, after
  // Per axis: the believed model without removing the logging delay (trace mode).
  std::map<std::string, double> per_axis_unaligned_rms_mm;
};

struct Whiteness {
  std::vector<double> autocorrelation;  // lags 1..10 of the remaining residual
  double ljung_box_q = 0.0;
  int lags = 10;
  double p_value = 1.0;
  bool white = true;  // p >= 0.01
};

// The measured tool-centre point against the believed kinematics applied
// to the recorded joints (docs/diagnosis.md, "Tool-centre point").
struct TcpComparison {
  bool present = false;
  bool datum_known = false;
  std::array<double, 3> offset_mm{};       // constant removed (zero with a known datum)
  std::array<double, 3> noise_floor_mm{};  // per component, as for the joints
  FitFigures train, heldout;               // per_axis keys tcp_x, tcp_y, tcp_z
};

// Series kept for the report's plots (train recording, aligned).
struct AxisSeries {
  std::string axis;
  std::vector<double> t_s, cmd, velocity, before_mm, after_mm;
  std::vector<char> heldout;  // 1 where the sample belongs to the held-out block
};

// A single recorded sample inconsistent with its neighbours (isolated_glitches
// in diagnose_steps.hpp): left out of every fit and statistic.
struct GlitchRow {
  std::size_t row = 0;        // data row of the recording, 0 = the first after the header
  std::string column;         // <j>_cmd, <j>_act or <j>_meas
  double deviation_mm = 0.0;  // from the nearer of the two one-sided predictions
};

struct DiagnosisResult {
  std::string recording, holdout_recording, map;
  std::size_t rows = 0;
  std::size_t excluded_samples = 0;    // around implausible command jumps and glitch rows
  std::vector<GlitchRow> glitch_rows;  // isolated samples off their neighbours, by row
  double sample_period_s = 0.0;        // median
  int substeps = 1;                    // for the median interval
  double delay_s = 0.0;
  std::optional<std::pair<double, double>> delay_ci95_s;
  std::string delay_note;
  double noise_floor_mm = 0.0;  // RMS over the axes' floors
  std::vector<AxisStats> axes;
  std::vector<Mismatch> mismatch;
  std::vector<Explanation> explanations;
  std::vector<NotIdentifiable> not_identifiable;
  std::vector<NotConfirmed> not_confirmed;
  std::vector<std::string> candidates_tested;
  FitFigures train, heldout;
  bool has_heldout = false;
  std::string heldout_kind;  // "file" or "split"
  Whiteness whiteness;
  TcpComparison tcp;
  std::string verdict;  // one line: "nothing missing" or the effects found
  // What this recording cannot show and why (e.g. effects the encoder does
  // not see, transients shorter than the sampling).
  std::vector<std::string> notes;
  std::vector<AxisSeries> series;
  sim::MachineDescription believed, fitted;
};

struct DiagnosisError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The ideal machine for a recording: the joints it carries, travel covering
// its commands, default drives, every effect off (actual = commanded).
sim::MachineDescription ideal_machine_for(const Recording& rec);

// The servo periods one re-simulation of a joint over `rec` takes: each
// recorded interval in equal sub-steps of at most `max_servo_period_s`, as
// the diagnosis splits them (DiagnosisOptions::max_servo_period_s). The fit
// re-simulates each joint hundreds of times; a budget is checked on this.
double servo_periods_per_run(const Recording& rec, double max_servo_period_s);

// Throws DiagnosisError on input that cannot be diagnosed (no joint with a
// command and a target, too few samples).
DiagnosisResult diagnose(const Recording& train, const Recording* holdout,
                         const sim::MachineDescription& believed, const DiagnosisOptions& options);

std::string diagnosis_json(const DiagnosisResult& result);
std::string diagnosis_html(const DiagnosisResult& result);
std::string diagnosis_summary(const DiagnosisResult& result);  // for stdout
// One line listing the glitch rows (empty when there are none).
std::string glitch_rows_text(const DiagnosisResult& result);

}  // namespace truecut::analysis::diagnosis
