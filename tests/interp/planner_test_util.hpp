// Helpers for the planner suites: plan G-code text, run the interpolator
// over a whole plan cycle by cycle, and check the sampled setpoints against
// the machine limits by finite differences (what a drive sees).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "interp_test_util.hpp"
#include "rs274_oracle.hpp"
#include "run_process.hpp"
#include "test_paths.hpp"
#include "truecut/interp/interpolator.hpp"
#include "truecut/interp/planner.hpp"

namespace truecut::interp::testing {

inline Plan plan_text(const std::string& text, const PlannerOptions& options = {}) {
  return plan_program(run(text), options);
}

// Every cycle of a plan, from the first setpoint to `done`.
inline std::vector<CycleOutput> sample_plan(const Plan& plan, double period_s,
                                            size_t max_cycles = 20'000'000) {
  auto channel = std::make_unique<PlanChannel>();
  Interpolator ip;
  std::vector<CycleOutput> out;
  size_t next = 0;
  while (out.size() < max_cycles) {
    while (next < plan.segments.size() && channel->try_push(plan.segments[next]))
      ++next;
    const CycleOutput& o = ip.step(*channel, period_s);
    EXPECT_FALSE(o.underrun);
    out.push_back(o);
    if (o.done) break;
  }
  return out;
}

struct LimitCheck {
  double worst_ratio[3] = {0, 0, 0};  // velocity, acceleration, jerk: largest value / limit
  int worst_axis[3] = {0, 0, 0};
  size_t worst_cycle[3] = {0, 0, 0};
  bool ok(double slack = 1e-6) const {
    return worst_ratio[0] <= 1 + slack && worst_ratio[1] <= 1 + slack &&
           worst_ratio[2] <= 1 + slack;
  }
  std::string describe(const std::vector<CycleOutput>& s) const {
    std::ostringstream o;
    const char* what[3] = {"velocity", "acceleration", "jerk"};
    const char* axis = "XYZAC";
    for (int k = 0; k < 3; ++k)
      o << what[k] << " " << worst_ratio[k] << " of limit on " << axis[worst_axis[k]]
        << " at cycle " << worst_cycle[k] << " (line "
        << (worst_cycle[k] < s.size() ? s[worst_cycle[k]].line : -1) << "); ";
    return o.str();
  }
};

// Finite differences of the joint setpoints over consecutive cycles.
inline LimitCheck check_limits(const std::vector<CycleOutput>& s, const MachineLimits& lim,
                               double period_s) {
  LimitCheck c;
  auto note = [&](int k, int j, size_t n, double value, double limit) {
    const double r = std::abs(value) / limit;
    if (r > c.worst_ratio[k]) c.worst_ratio[k] = r, c.worst_axis[k] = j, c.worst_cycle[k] = n;
  };
  const double t = period_s;
  for (size_t n = 1; n < s.size(); ++n)
    for (int j = 0; j < 5; ++j) {
      const auto& l = lim.axis[j];
      const double q0 = s[n].joints[j], q1 = s[n - 1].joints[j];
      note(0, j, n, (q0 - q1) / t, l.max_velocity);
      if (n >= 2) {
        const double q2 = s[n - 2].joints[j];
        note(1, j, n, (q0 - 2 * q1 + q2) / (t * t), l.max_acceleration);
        if (n >= 3) {
          const double q3 = s[n - 3].joints[j];
          note(2, j, n, (q0 - 3 * q1 + 3 * q2 - q3) / (t * t * t), l.max_jerk);
        }
      }
    }
  return c;
}

// LinuxCNC's sample programs, from the package of the rs274 oracle
// (rs274_oracle.hpp); nullopt with the reason when unavailable.
inline std::optional<std::filesystem::path> linuxcnc_share(std::string& why) {
  const auto& oracle = rs274_oracle(why);
  if (!oracle) return std::nullopt;
  return oracle->share;
}

inline std::filesystem::path five_axis_demo(const std::filesystem::path& share, const char* name) {
  return share /
         "doc/linuxcnc/examples/sample-configs/sim/axis/vismach/5axis/table-rotary-tilting/demos" /
         name;
}

// The demo's text with the kinematics-switching remaps M428-M430 replaced:
// by TRAORI (M428 selects TCP kinematics there) when `tcp`, else dropped.
inline std::string demo_text(const std::filesystem::path& file, bool tcp) {
  std::ifstream in(file);
  std::string text, line;
  static const std::regex remap(R"(^\s*[mM]4(28|29|30)\b.*)");
  while (std::getline(in, line)) {
    if (std::regex_match(line, remap)) {
      if (tcp && (line.find("428") != std::string::npos)) text += "TRAORI\n";
      continue;
    }
    text += line + "\n";
  }
  return text;
}

}  // namespace truecut::interp::testing
