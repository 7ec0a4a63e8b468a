// Standstill windows after an approach → ISO 230-2 readings.
//
// The command only bounds a window (it holds one value while the axis is
// asked to be at one target); when the axis is at rest, which way it came
// from, and whether it is a new approach are taken from the measured
// position. So a command that is a target setpoint (it jumps at once to the
// next target and the axis then travels there) and a trajectory setpoint
// (it moves with the axis) give the same readings (docs/iso230.md).
#include <algorithm>
#include <cmath>
#include <cstddef>

#include "truecut/analysis/iso230_positioning.hpp"

namespace truecut::analysis {
namespace {

struct Rest {
  std::size_t from, to;  // samples at rest
};

// The longest run of samples in [first, last] over which the measured
// position is at rest: each sample moved by no more than V·Δt + T/2 since
// the latest sample of the run at least τ = min_dwell/2 earlier (the run's
// first sample while the run is shorter), and the command changed by no more
// than T/2 from the sample before (a logged trajectory may show a departure
// before the measured position does). Over a span of τ the noise of a
// reading hardly looks like speed, while travel does at once. A sample that
// moved starts a new run. Of equally long runs, the last.
Rest at_rest(const std::vector<double>& t, const std::vector<double>& c,
             const std::vector<double>& m, std::size_t first, std::size_t last,
             const StandstillOptions& o) {
  const double tau = 0.5 * o.min_dwell_s, floor = 0.5 * o.target_tolerance;
  Rest best{first, first};
  std::size_t from = first, j = first;
  for (std::size_t k = first + 1; k <= last + 1; ++k) {
    bool moving = true;
    if (k <= last) {
      while (j + 1 < k && t[j + 1] <= t[k] - tau)
        ++j;
      moving = std::abs(m[k] - m[j]) > o.velocity_threshold * (t[k] - t[j]) + floor ||
               std::abs(c[k] - c[k - 1]) > floor;
    }
    if (!moving) continue;
    if (t[k - 1] - t[from] >= t[best.to] - t[best.from]) best = {from, k - 1};
    from = j = k;
  }
  return best;
}

}  // namespace

std::vector<PositionReading> find_position_readings(const std::vector<double>& t_s,
                                                    const std::vector<double>& cmd,
                                                    const std::vector<double>& measured,
                                                    const StandstillOptions& o) {
  std::vector<PositionReading> out;
  const std::size_t n = t_s.size();
  if (n < 2 || cmd.size() != n || measured.size() != n) return out;
  auto still = [&](std::size_t i) {  // sample i-1 → i without a command change
    return std::abs(cmd[i] - cmd[i - 1]) <= o.velocity_threshold * (t_s[i] - t_s[i - 1]);
  };
  std::size_t previous_first = 0;    // first sample of the previous window
  std::size_t previous_settled = 0;  // first sample at rest of the previous window
  std::size_t i = 1;
  while (i < n) {
    if (!still(i)) {
      ++i;
      continue;
    }
    const std::size_t first = i - 1;
    while (i < n && still(i))
      ++i;
    const std::size_t last = i - 1;
    // The axis may still travel after the command stopped changing (a target
    // setpoint, servo lag) or leave before a logged command shows it: the
    // reading window is where the measured position is at rest.
    const Rest rest_run = at_rest(t_s, cmd, measured, first, last, o);
    const std::size_t settled = rest_run.from, end = rest_run.to;
    if (t_s[end] - t_s[settled] < o.min_dwell_s) continue;

    const double settle_t = t_s[settled] + o.settle_fraction * (t_s[end] - t_s[settled]);
    double sum_cmd = 0, sum_meas = 0;
    int count = 0;
    for (std::size_t k = settled; k <= end; ++k) {
      if (t_s[k] < settle_t) continue;
      sum_cmd += cmd[k];
      sum_meas += measured[k];
      ++count;
    }
    const double target = sum_cmd / count;
    const double rest = sum_meas / count;
    double spread = 0;  // RMS of the measured position about its rest
    for (std::size_t k = settled; k <= end; ++k)
      if (t_s[k] >= settle_t) spread += (measured[k] - rest) * (measured[k] - rest) / count;
    spread = std::sqrt(spread);
    // The approach side is where the measured position last was outside the
    // tolerance band (or 6 × its spread at rest) about its rest position
    // before the command began to hold this target (settling inside the
    // window is no approach); if it never left the band since the previous
    // window began, this window continues that one and is no new approach.
    const double band = std::max(o.target_tolerance, 6 * spread);
    int direction = 0;
    for (std::size_t k = first; k-- > previous_first;) {
      if (std::abs(measured[k] - rest) > band) {
        direction = measured[k] < rest ? +1 : -1;
        break;
      }
    }
    previous_first = first;
    const double travel = std::abs(rest - measured[previous_settled]);
    previous_settled = settled;
    if (direction == 0) continue;
    // A target setpoint: the command reached the target in one step, at
    // least half the travel from the previous rest, which the measured
    // position did not follow in that step.
    const double step = first > 0 ? std::abs(cmd[first] - cmd[first - 1]) : 0.0;
    const bool jump = step > 10 * o.target_tolerance && step >= 0.5 * travel &&
                      step > 3 * std::abs(measured[first] - measured[first - 1]);
    PositionReading r;
    r.t_start_s = t_s[settled];
    r.t_end_s = t_s[end];
    r.target = target;
    r.measured = rest;
    r.direction = direction;
    r.target_setpoint = jump;
    out.push_back(r);
  }
  return out;
}

}  // namespace truecut::analysis
