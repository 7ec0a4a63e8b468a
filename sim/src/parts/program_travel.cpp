#include "truecut/sim/program_travel.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "truecut/interp/plan_segment.hpp"
#include "truecut/rt/core/kinematics_ac.hpp"
#include "truecut/rt/number_format.hpp"
#include "truecut/sim/true_tool_pose.hpp"

namespace truecut::sim {
namespace {

constexpr double kEpsilon = 1e-9;  // rounding slack at the travel ends

// Three decimals at most, trailing zeros dropped: "12.5", "-0.001", "0".
std::string format_number(double v) {
  std::string s = rt::format_fixed(v, 3);
  while (!s.empty() && s.back() == '0')
    s.pop_back();
  if (!s.empty() && s.back() == '.') s.pop_back();
  return s;
}

std::string joint_label(int joint) {
  std::string s(kJointNames[joint]);
  for (char& c : s)
    c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

// The joints at planning-space point p of segment s, as the interpolator
// maps it (joint space: the point itself; TCP mode: inverse kinematics with
// the interpolated angles as hint).
rt::AcJoints joints_at(const interp::PlanSegment& s, const interp::Vec5& p,
                       const rt::AcJoints& previous) {
  const double w = s.rotary_weight_mm_per_deg;
  const double a = p[3] / w, c = p[4] / w;
  if (!s.tcp) return {p[0], p[1], p[2], a, c};
  rt::ToolPose pose = rt::forward_ac(s.kinematics, rt::AcJoints{0, 0, 0, a, c});
  pose.tcp_mm = {p[0], p[1], p[2]};
  rt::AcJoints hint = previous;
  hint.a_deg = a;
  hint.c_deg = c;
  return rt::inverse_ac(s.kinematics, pose, hint).joints;
}

int sample_count(const interp::PlanSegment& s, const TravelCheckOptions& o) {
  const double length = s.law.length;
  if (!s.tcp && s.piece.kind == interp::PathPiece::kLine) return 1;
  int n = std::max(1, static_cast<int>(std::ceil(length / o.max_step_mm)));
  if (s.piece.kind == interp::PathPiece::kArc && s.piece.length > 0) {
    const double sweep_deg =
        std::abs(s.piece.sweep_rad) * 180.0 / std::numbers::pi * length / s.piece.length;
    n = std::max(n, static_cast<int>(std::ceil(sweep_deg / o.max_arc_step_deg)));
  }
  return std::min(n, 1 << 24);
}

}  // namespace

interp::PlannerOptions planner_options_for(const MachineParams& machine) {
  interp::PlannerOptions o;
  o.kinematics = nominal_ac_params(machine);
  return o;
}

ProgramTravel program_travel(const interp::Plan& plan, const MachineParams& machine,
                             const std::string& program_name, const TravelCheckOptions& options) {
  if (!(options.max_step_mm > 0) || !(options.max_arc_step_deg > 0))
    throw std::invalid_argument("program_travel: sample steps must be positive");
  ProgramTravel r;
  r.min.fill(std::numeric_limits<double>::infinity());
  r.max.fill(-std::numeric_limits<double>::infinity());
  const auto visit = [&](const rt::AcJoints& q, int line) {
    const std::array<double, kJointCount> v{q.x_mm, q.y_mm, q.z_mm, q.a_deg, q.c_deg};
    ++r.samples;
    for (int j = 0; j < kJointCount; ++j) {
      r.min[j] = std::min(r.min[j], v[j]);
      r.max[j] = std::max(r.max[j], v[j]);
      if (r.first_excursion) continue;
      const JointParams& jp = machine.joints[j];
      const double lo = jp.present ? jp.min : 0.0, hi = jp.present ? jp.max : 0.0;
      if (v[j] >= lo - kEpsilon && v[j] <= hi + kEpsilon) continue;
      TravelExcursion e;
      e.line = line;
      e.joint = j;
      e.position = v[j];
      e.min = lo;
      e.max = hi;
      e.message = program_name + ":" + std::to_string(line) + ": joint " + joint_label(j) +
                  " leaves travel [" + format_number(lo) + ", " + format_number(hi) + "] at " +
                  format_number(v[j]) + " " + std::string(joint_unit(j));
      r.first_excursion = e;
    }
  };
  rt::AcJoints previous{};
  for (const interp::PlanSegment& s : plan.segments) {
    if (s.kind != interp::SegmentKind::kMotion) continue;
    const int n = sample_count(s, options);
    for (int i = 0; i <= n; ++i) {
      const double u = s.u0 + s.law.length * i / n;
      previous = joints_at(s, interp::evaluate(s.piece, u), previous);
      visit(previous, s.line);
    }
  }
  if (r.samples == 0) {
    r.min.fill(0);
    r.max.fill(0);
  }
  return r;
}

ProgramTravel program_travel(const interp::CanonProgram& program, const MachineParams& machine,
                             const std::string& program_name, const TravelCheckOptions& options) {
  return program_travel(interp::plan_program(program, planner_options_for(machine)), machine,
                        program_name, options);
}

}  // namespace truecut::sim
