// A recording prepared for re-simulation: commands of every joint, the
// recorded target of the joints that have one, and the re-simulation of
// the commands through a machine model at the recording's own time steps.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "truecut/analysis/diagnosis/diagnosis.hpp"
#include "truecut/analysis/recording.hpp"
#include "truecut/sim/machine_description.hpp"

namespace truecut::analysis::diagnosis {

struct Trace {
  std::string file;
  std::vector<double> t_s;
  std::array<std::vector<double>, sim::kJointCount> cmd;  // empty: joint not commanded (held at 0)
  // d cmd / dt at each sample for a cubic Hermite command between samples;
  // empty: the command is linear between samples.
  std::array<std::vector<double>, sim::kJointCount> cmd_slope;
  std::array<std::vector<double>, sim::kJointCount> target;  // recorded _meas or _act, empty: none
  std::array<bool, sim::kJointCount> meas{};                 // target is <j>_meas
  std::vector<double> spindle_power_kw;                      // empty: none
  std::vector<double> line;                                  // empty: none
  std::vector<double> tool;                                  // tool number; empty: none
  std::vector<int> axes;                                     // joints with cmd and target
  // An external measurement of the true tool-centre point (tcp_true_x/y/z,
  // workpiece frame), all three or none, and the recorded joint positions
  // the believed kinematics turn into a TCP: <j>_meas, else <j>_act, else
  // <j>_cmd; empty: the joint is not in the recording (held at 0).
  std::array<std::vector<double>, 3> tcp;
  std::array<std::vector<double>, sim::kJointCount> joint_pos;
  bool has_tcp() const { return !tcp[0].empty(); }
  std::size_t rows() const { return t_s.size(); }
};

Trace make_trace(const Recording& rec, DiagnosisOptions::CommandInterpolation interpolation =
                                           DiagnosisOptions::CommandInterpolation::kCubic);

// Slopes for a cubic Hermite command through (t, y): the three-point
// derivative (the parabola through three samples: exact for a constant
// acceleration, and a reversal may turn between two samples, as a real one
// does), zero next to a standstill (a start or stop is no reversal), limited
// by Fritsch–Carlson between samples that do not enclose a turn (no
// overshoot).
std::vector<double> command_slopes(const std::vector<double>& t, const std::vector<double>& y);

// What the model says the recorder would have seen, per joint.
struct Simulated {
  std::array<std::vector<double>, sim::kJointCount> target;  // same meaning as Trace::target
  std::array<std::vector<double>, sim::kJointCount> motor;   // encoder (motor-side) position
};

// Joint re-simulations of one trace kept for reuse. A joint's motion
// depends only on its own parameters (sim::MachineModel::step_joint), so a
// model that differs from an earlier one in another joint's effects (a
// column of a Jacobian, a candidate) re-simulates only the joints that
// changed; the rest is read back, bit for bit. The most recent runs per
// joint are kept, as many as fit in kBytesPerJoint (at least kMinRuns, at
// most runs_per_joint): a fit returns to a model it left several columns or
// candidates ago, and a run of a short recording is small (1055 rows:
// 17 kB) while it costs tens of milliseconds to simulate again. Safe to
// share between threads.
class ResimCache {
 public:
  static constexpr std::size_t kBytesPerJoint = std::size_t{16} << 20;
  static constexpr std::size_t kMinRuns = 6;
  explicit ResimCache(std::size_t runs_per_joint = SIZE_MAX) : max_runs_(runs_per_joint) {}
  ResimCache(const ResimCache&) = delete;
  ResimCache& operator=(const ResimCache&) = delete;

  struct Run {
    sim::MachineParams key;  // the joint's part of the parameters (joint_part)
    std::vector<double> motor, truth;
  };
  // The run of joint j for `key` on (trace, max_period_s), or null.
  std::shared_ptr<const Run> find(const Trace& trace, double max_period_s, int j,
                                  const sim::MachineParams& key);
  void put(const Trace& trace, double max_period_s, int j, std::shared_ptr<const Run> run);

 private:
  std::mutex mutex_;
  const Trace* trace_ = nullptr;
  std::size_t rows_ = 0;
  double max_period_s_ = 0.0;
  std::size_t max_runs_;
  std::size_t capacity_ = 0;  // for the bound trace
  std::array<std::vector<std::shared_ptr<const Run>>, sim::kJointCount> runs_;  // most recent last
  void bind(const Trace& trace, double max_period_s);
};

// Each recorded interval dt is simulated in ceil(dt / max_period_s) equal
// servo periods, the command interpolated between the samples (cubic Hermite
// with trace.cmd_slope, else linear); the output of the first period of an
// interval is the sample at its start. Joint by joint (the linear slides'
// geometric errors applied afterwards), as sim::MachineModel::step would;
// with a cache, the joints whose parameters it has seen are read back.
Simulated resimulate(const sim::MachineParams& params, const Trace& trace, double max_period_s,
                     ResimCache* cache = nullptr);
// The parameters joint j's motion depends on (its drive and its effects),
// everything else at its default: equal for two models whose joint j moves
// the same.
sim::MachineParams joint_part(const sim::MachineParams& params, int j);
int substeps_for(double dt_s, double max_period_s);

// A simulated series read at t − delay (cubic Hermite with the slopes of
// command_slopes, as the command is read between samples; held at the ends):
// the simulation shifted to match a recorder that logs late by delay.
std::vector<double> delayed(const std::vector<double>& t, const std::vector<double>& y,
                            double delay_s);
// Every target and motor series of `sim` delayed.
void delay_simulated(const std::vector<double>& t, Simulated& sim, double delay_s);

// Central-difference derivatives of a sampled signal.
std::vector<double> derivative(const std::vector<double>& t, const std::vector<double>& y);

double median_period(const std::vector<double>& t);

}  // namespace truecut::analysis::diagnosis
