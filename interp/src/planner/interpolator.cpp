#include "truecut/interp/interpolator.hpp"

#include <cmath>

#include "output_map.hpp"

namespace truecut::interp {

const CycleOutput& Interpolator::step(PlanChannel& channel, double period_s) noexcept {
  if (out_.done) return out_;
  if (!has_current_) {
    if (!channel.try_pop(current_)) return out_;  // nothing planned yet: stay put
    has_current_ = true;
    t_s_ = 0;
    if (!started_) {
      started_ = true;
      evaluate_current();  // the start point, so the first feed is not a jump
    }
  } else {
    t_s_ += period_s;
  }
  period_s_ = period_s;
  out_.underrun = false;
  for (int crossed = 0; t_s_ >= current_.law.duration_s && crossed < kMaxSegmentsPerCycle;
       ++crossed) {
    if (current_.last) {
      t_s_ = current_.law.duration_s;
      out_.done = true;
      break;
    }
    PlanSegment next;
    if (!channel.try_pop(next)) {
      // Hold the end of the segment; time does not advance until more arrives.
      t_s_ = current_.law.duration_s;
      out_.underrun = true;
      break;
    }
    t_s_ -= current_.law.duration_s;
    current_ = next;
  }
  evaluate_current();
  return out_;
}

void Interpolator::evaluate_current() noexcept {
  const LawState st = evaluate(current_.law, t_s_);
  const Vec5 p = evaluate(current_.piece, current_.u0 + st.s);
  const plan::MappedPoint mp = plan::map_point(current_.tcp, current_.kinematics,
                                               current_.rotary_weight_mm_per_deg, p, hint_);
  hint_ = mp.joints;
  const std::array<double, 3> tcp{mp.pose.tcp_mm.x(), mp.pose.tcp_mm.y(), mp.pose.tcp_mm.z()};
  if (period_s_ > 0) {
    const double dx = tcp[0] - out_.tcp_mm[0], dy = tcp[1] - out_.tcp_mm[1],
                 dz = tcp[2] - out_.tcp_mm[2];
    out_.feed_mm_per_s = std::sqrt(dx * dx + dy * dy + dz * dz) / period_s_;
  }
  out_.tcp_mm = tcp;
  out_.tool_axis = {mp.pose.axis.x(), mp.pose.axis.y(), mp.pose.axis.z()};
  out_.joints = {mp.joints.x_mm, mp.joints.y_mm, mp.joints.z_mm, mp.joints.a_deg, mp.joints.c_deg};
  out_.line = current_.line;
  out_.tool = current_.tool;
  out_.spindle_rpm = current_.spindle_rpm;
  out_.tool_length_mm = current_.kinematics.tool_length_mm;
  out_.operation = current_.operation;
  out_.tcp_mode = current_.tcp;
}

}  // namespace truecut::interp
