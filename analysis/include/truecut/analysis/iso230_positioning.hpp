// ISO 230-2:2014 evaluation of positioning accuracy and repeatability of a
// numerically controlled axis, computed from a recording: targets and
// approach directions are found from standstill windows (docs/iso230.md).
// All lengths are in the axis unit: mm for x y z, degrees for a and c.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "truecut/analysis/recording.hpp"

namespace truecut::analysis {

struct StandstillOptions {
  double velocity_threshold = 0.01;  // |d cmd/dt| below this is standstill (unit/s)
  double min_dwell_s = 0.5;          // shorter standstills are not readings
  double target_tolerance = 0.001;   // commanded positions closer than this are one target
  double settle_fraction = 0.5;      // the reading averages the window after this fraction
  int min_runs = 2;                  // approaches per direction for a target to count
};

// One reading: a standstill after an approach. Standstill, approach
// direction and the start of the reading come from the measured position;
// the command only bounds the window (it holds one value), so target and
// trajectory setpoints both work (docs/iso230.md).
struct PositionReading {
  double t_start_s = 0, t_end_s = 0;
  double target = 0;    // mean <j>_cmd over the averaged part of the window
  double measured = 0;  // mean <j>_meas (else <j>_act) over the same samples
  int direction = 0;    // +1 approached moving positive (↑), -1 negative (↓)
  // The command jumped to the target in one step and the axis travelled
  // there afterwards (a target setpoint, not a trajectory setpoint).
  bool target_setpoint = false;
  double deviation() const { return measured - target; }
};

// Finds the readings of one axis in time order.
std::vector<PositionReading> find_position_readings(const std::vector<double>& t_s,
                                                    const std::vector<double>& cmd,
                                                    const std::vector<double>& measured,
                                                    const StandstillOptions& options);

struct DirectionStats {
  std::vector<double> deviations;  // x_ij, in run order
  double mean = 0;                 // x̄_i↑ or x̄_i↓
  double s = 0;                    // s_i (n-1 in the denominator); 0 for one run
  double R = 0;                    // 4 s_i
  int runs() const { return static_cast<int>(deviations.size()); }
};

struct TargetResult {
  double target = 0;  // P_i
  std::optional<DirectionStats> up, down;
  std::optional<double> mean_bidirectional;  // x̄_i
  std::optional<double> B;                   // B_i = x̄_i↑ − x̄_i↓
  std::optional<double> R;                   // R_i
};

struct DirectionSummary {
  double A = 0, E = 0, R = 0;
};

struct AxisPositioning {
  std::string joint;
  bool rotary = false;
  std::string measured_channel;  // <j>_meas or <j>_act
  std::vector<TargetResult> targets;
  std::size_t readings = 0;  // standstill readings found before grouping
  std::optional<DirectionSummary> up, down;
  // Bidirectional results; empty for a unidirectional test.
  std::optional<double> A, E, M, R, B, B_mean;
  std::vector<std::string> notes;
};

// Groups the readings into targets and evaluates ISO 230-2. nullopt when no
// target has min_runs approaches in any direction.
std::optional<AxisPositioning> evaluate_positioning(const std::string& joint,
                                                    const std::vector<PositionReading>& readings,
                                                    const StandstillOptions& options);

// Both steps for one joint of a recording (needs <j>_cmd and <j>_meas or
// <j>_act; throws RecordingError otherwise).
std::optional<AxisPositioning> evaluate_positioning(const Recording& recording,
                                                    const std::string& joint,
                                                    const StandstillOptions& options);

}  // namespace truecut::analysis
