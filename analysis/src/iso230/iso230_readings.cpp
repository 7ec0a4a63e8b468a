// Standstill windows after an approach → ISO 230-2 readings.
#include <cmath>
#include <cstddef>

#include "truecut/analysis/iso230_positioning.hpp"

namespace truecut::analysis {

std::vector<PositionReading> find_position_readings(const std::vector<double>& t_s,
                                                    const std::vector<double>& cmd,
                                                    const std::vector<double>& measured,
                                                    const StandstillOptions& o) {
  std::vector<PositionReading> out;
  const std::size_t n = t_s.size();
  if (n < 2 || cmd.size() != n || measured.size() != n) return out;
  auto still = [&](std::size_t i) {  // sample i-1 → i without motion
    return std::abs(cmd[i] - cmd[i - 1]) <= o.velocity_threshold * (t_s[i] - t_s[i - 1]);
  };
  std::size_t previous_first = 0;  // first sample of the previous window
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
    if (t_s[last] - t_s[first] < o.min_dwell_s) continue;

    const double settle_t = t_s[first] + o.settle_fraction * (t_s[last] - t_s[first]);
    double sum_cmd = 0, sum_meas = 0;
    int count = 0;
    for (std::size_t k = first; k <= last; ++k) {
      if (t_s[k] < settle_t) continue;
      sum_cmd += cmd[k];
      sum_meas += measured[k];
      ++count;
    }
    const double target = sum_cmd / count;
    // The approach side is where the command last was outside the target's
    // tolerance band; if it never left the band since the previous window
    // began, this window continues that one and is no new approach.
    int direction = 0;
    for (std::size_t k = first; k-- > previous_first;) {
      if (std::abs(cmd[k] - target) > o.target_tolerance) {
        direction = cmd[k] < target ? +1 : -1;
        break;
      }
    }
    previous_first = first;
    if (direction == 0) continue;
    out.push_back({t_s[first], t_s[last], target, sum_meas / count, direction});
  }
  return out;
}

}  // namespace truecut::analysis
