// The per-cycle interpolator: evaluates the plan at the current time and
// reports the tool pose. Real-time safe: no allocation, no locks, no
// exceptions, bounded work (at most kMaxSegmentsPerCycle segments are
// crossed in one cycle).
//
// Segments arrive through a lock-free channel from the non-real-time
// planner side; when the channel runs dry before the last segment the
// interpolator holds the last position and raises `underrun`.
#pragma once

#include <array>
#include <cstdint>

#include "truecut/interp/plan_segment.hpp"
#include "truecut/rt/channel.hpp"

namespace truecut::interp {

inline constexpr std::size_t kPlanChannelCapacity = 4096;
using PlanChannel = rt::SpscChannel<PlanSegment, kPlanChannelCapacity>;

struct CycleOutput {
  std::array<double, 3> tcp_mm{};            // tool-centre point, workpiece frame
  std::array<double, 3> tool_axis{0, 0, 1};  // unit, TCP -> spindle, workpiece frame
  std::array<double, 5> joints{};            // x y z (mm) a c (deg), machine
  double feed_mm_per_s = 0;   // speed of the TCP relative to the workpiece this cycle
  double spindle_rpm = 0;     // commanded spindle speed, 0 while stopped
  double tool_length_mm = 0;  // length offset in use (G43), as the kinematics see it
  std::int32_t line = 0;
  std::int32_t tool = 0;
  std::int32_t operation = 0;
  bool tcp_mode = false;
  bool done = false;      // the last segment has been completed
  bool underrun = false;  // the channel ran dry before the program end
};

class Interpolator {
 public:
  static constexpr int kMaxSegmentsPerCycle = 256;

  // Advances by one servo period and evaluates the plan there. Until the
  // first segment arrives the output stays at its initial value.
  const CycleOutput& step(PlanChannel& channel, double period_s) noexcept;
  const CycleOutput& output() const noexcept { return out_; }

 private:
  void evaluate_current() noexcept;

  PlanSegment current_{};
  bool has_current_ = false;
  bool started_ = false;
  double t_s_ = 0;  // time inside current_
  CycleOutput out_{};
  rt::AcJoints hint_{};
  double period_s_ = 0;
};

}  // namespace truecut::interp
