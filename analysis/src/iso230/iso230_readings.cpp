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

// Noise of the measured position at rest: the smallest RMS of eight
// consecutive sample-to-sample changes in [first, last], over √2. Changes of
// exactly zero (a value held between two log entries) are left out.
double rest_noise(const std::vector<double>& m, std::size_t first, std::size_t last) {
  std::vector<double> d;
  for (std::size_t k = first + 1; k <= last; ++k)
    if (m[k] != m[k - 1]) d.push_back(m[k] - m[k - 1]);
  if (d.empty()) return 0.0;
  const std::size_t chunk = std::min<std::size_t>(8, d.size());
  double best = INFINITY;
  for (std::size_t b = 0; b + chunk <= d.size(); ++b) {
    double ss = 0;
    for (std::size_t k = b; k < b + chunk; ++k)
      ss += d[k] * d[k];
    best = std::min(best, std::sqrt(ss / double(chunk) / 2));
  }
  return best;
}

struct Rest {
  std::size_t from, to;  // samples at rest
  double band;           // noise band of the measured position at rest
};

// The longest run of samples in [first, last] over which the measured
// position is at rest: no step between neighbours larger than V·Δt plus the
// noise band (8 × the rest noise, at least half the target tolerance). Of
// equally long runs, the last.
Rest at_rest(const std::vector<double>& t, const std::vector<double>& m, std::size_t first,
             std::size_t last, const StandstillOptions& o) {
  const double band = std::max(8 * rest_noise(m, first, last), 0.5 * o.target_tolerance);
  Rest best{first, first, band};
  std::size_t from = first;
  for (std::size_t k = first + 1; k <= last + 1; ++k) {
    const bool moved =
        k > last || std::abs(m[k] - m[k - 1]) > o.velocity_threshold * (t[k] - t[k - 1]) + band;
    if (!moved) continue;
    if (t[k - 1] - t[from] >= t[best.to] - t[best.from]) best = {from, k - 1, band};
    from = k;
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
  std::size_t previous_settled = 0;  // first settled sample of the previous window
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
    const Rest rest_run = at_rest(t_s, measured, first, last, o);
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
    // The approach side is where the measured position last was outside the
    // tolerance band (or noise band) about its rest position; if it never left the band
    // since the previous window came to rest, this window continues that
    // one and is no new approach.
    const double band = std::max(o.target_tolerance, rest_run.band);
    int direction = 0;
    for (std::size_t k = settled; k-- > previous_settled;) {
      if (std::abs(measured[k] - rest) > band) {
        direction = measured[k] < rest ? +1 : -1;
        break;
      }
    }
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
