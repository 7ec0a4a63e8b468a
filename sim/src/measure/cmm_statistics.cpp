#include <algorithm>
#include <cmath>
#include <map>

#include "truecut/sim/measure/cmm.hpp"

namespace truecut::sim::measure {
namespace {

SurfaceDeviationStats statistics_of(int surface, std::size_t points,
                                    std::vector<double> deviations_um) {
  SurfaceDeviationStats s;
  s.surface = surface;
  s.points = points;
  s.valid = deviations_um.size();
  if (deviations_um.empty()) return s;
  const double n = static_cast<double>(deviations_um.size());
  double sum = 0, sum_sq = 0;
  for (double d : deviations_um) {
    sum += d;
    sum_sq += d * d;
  }
  s.mean_um = sum / n;
  s.rms_um = std::sqrt(sum_sq / n);
  if (deviations_um.size() > 1) {
    double centred = 0;
    for (double d : deviations_um)
      centred += (d - s.mean_um) * (d - s.mean_um);
    s.std_um = std::sqrt(centred / (n - 1));
  }
  for (double& d : deviations_um)
    d = std::abs(d);
  std::sort(deviations_um.begin(), deviations_um.end());
  s.max_abs_um = deviations_um.back();
  const double rank = 0.95 * (n - 1);
  const auto lo = static_cast<std::size_t>(std::floor(rank));
  const std::size_t hi = std::min(lo + 1, deviations_um.size() - 1);
  s.p95_abs_um = deviations_um[lo] +
                 (rank - static_cast<double>(lo)) * (deviations_um[hi] - deviations_um[lo]);
  return s;
}

}  // namespace

std::vector<SurfaceDeviationStats> surface_statistics(
    std::span<const CmmMeasurement> measurements) {
  std::map<int, std::pair<std::size_t, std::vector<double>>> by_surface;
  for (const CmmMeasurement& m : measurements) {
    auto& entry = by_surface[m.nominal.surface];
    ++entry.first;
    if (m.valid) entry.second.push_back(m.deviation_mm * 1000.0);
  }
  std::vector<SurfaceDeviationStats> out;
  for (auto& [surface, entry] : by_surface)
    out.push_back(statistics_of(surface, entry.first, std::move(entry.second)));
  return out;
}

SurfaceDeviationStats overall_statistics(std::span<const CmmMeasurement> measurements) {
  std::vector<double> deviations_um;
  for (const CmmMeasurement& m : measurements)
    if (m.valid) deviations_um.push_back(m.deviation_mm * 1000.0);
  return statistics_of(-1, measurements.size(), std::move(deviations_um));
}

}  // namespace truecut::sim::measure
