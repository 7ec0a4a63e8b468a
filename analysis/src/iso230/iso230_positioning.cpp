// ISO 230-2:2014 statistics per target and per axis (formulas in docs/iso230.md).
#include "truecut/analysis/iso230_positioning.hpp"

#include <algorithm>
#include <cmath>

namespace truecut::analysis {
namespace {

DirectionStats stats(std::vector<double> deviations) {
  DirectionStats d;
  d.deviations = std::move(deviations);
  const double n = double(d.deviations.size());
  for (double x : d.deviations)
    d.mean += x / n;
  if (d.deviations.size() > 1) {
    double ss = 0;
    for (double x : d.deviations)
      ss += (x - d.mean) * (x - d.mean);
    d.s = std::sqrt(ss / (n - 1));
  }
  d.R = 4 * d.s;
  return d;
}

struct Group {
  double target_sum = 0;
  int count = 0;
  std::vector<double> up, down;
  double target() const { return target_sum / count; }
};

std::vector<Group> group_by_target(std::vector<PositionReading> readings, double tolerance) {
  std::stable_sort(readings.begin(), readings.end(),
                   [](const auto& a, const auto& b) { return a.target < b.target; });
  std::vector<Group> groups;
  double last_target = 0;
  for (const auto& r : readings) {
    if (groups.empty() || r.target - last_target > tolerance) groups.emplace_back();
    last_target = r.target;
    auto& g = groups.back();
    g.target_sum += r.target;
    ++g.count;
    (r.direction > 0 ? g.up : g.down).push_back(r.deviation());
  }
  // Within a group the readings must stay in time order (run order).
  return groups;
}

// A↑/↓, E↑/↓, R↑/↓ over the targets that have that direction.
std::optional<DirectionSummary> summarize(const std::vector<TargetResult>& targets, bool upward) {
  std::optional<DirectionSummary> out;
  double hi_a = -INFINITY, lo_a = INFINITY, hi_e = -INFINITY, lo_e = INFINITY, r = 0;
  for (const auto& t : targets) {
    const auto& d = upward ? t.up : t.down;
    if (!d) continue;
    hi_a = std::max(hi_a, d->mean + 2 * d->s);
    lo_a = std::min(lo_a, d->mean - 2 * d->s);
    hi_e = std::max(hi_e, d->mean);
    lo_e = std::min(lo_e, d->mean);
    r = std::max(r, d->R);
    out = DirectionSummary{};
  }
  if (out) *out = {hi_a - lo_a, hi_e - lo_e, r};
  return out;
}

}  // namespace

std::optional<AxisPositioning> evaluate_positioning(const std::string& joint,
                                                    const std::vector<PositionReading>& readings,
                                                    const StandstillOptions& o) {
  // Readings arrive in time order; stable grouping keeps the run order.
  auto groups = group_by_target(readings, o.target_tolerance);
  const int need = std::max(1, o.min_runs);
  auto has = [&](const std::vector<double>& v) { return int(v.size()) >= need; };
  const bool any_bidirectional = std::any_of(
      groups.begin(), groups.end(), [&](const Group& g) { return has(g.up) && has(g.down); });

  AxisPositioning axis;
  axis.joint = joint;
  axis.rotary = is_rotary_joint(joint);
  axis.readings = readings.size();
  std::size_t dropped = 0;
  for (const auto& g : groups) {
    const bool keep = any_bidirectional ? has(g.up) && has(g.down) : has(g.up) || has(g.down);
    if (!keep) {
      ++dropped;
      continue;
    }
    TargetResult t;
    t.target = g.target();
    if (has(g.up)) t.up = stats(g.up);
    if (has(g.down)) t.down = stats(g.down);
    if (t.up && t.down) {
      t.mean_bidirectional = (t.up->mean + t.down->mean) / 2;
      t.B = t.up->mean - t.down->mean;
      t.R = std::max({2 * t.up->s + 2 * t.down->s + std::abs(*t.B), t.up->R, t.down->R});
    }
    axis.targets.push_back(std::move(t));
  }
  if (axis.targets.empty()) return std::nullopt;

  axis.up = summarize(axis.targets, true);
  axis.down = summarize(axis.targets, false);
  if (any_bidirectional) {
    double hi_a = -INFINITY, lo_a = INFINITY, hi_e = -INFINITY, lo_e = INFINITY;
    double hi_m = -INFINITY, lo_m = INFINITY, r = 0, b = 0, b_sum = 0;
    for (const auto& t : axis.targets) {
      for (const auto* d : {&*t.up, &*t.down}) {
        hi_a = std::max(hi_a, d->mean + 2 * d->s);
        lo_a = std::min(lo_a, d->mean - 2 * d->s);
        hi_e = std::max(hi_e, d->mean);
        lo_e = std::min(lo_e, d->mean);
      }
      hi_m = std::max(hi_m, *t.mean_bidirectional);
      lo_m = std::min(lo_m, *t.mean_bidirectional);
      r = std::max(r, *t.R);
      b = std::max(b, std::abs(*t.B));
      b_sum += *t.B;
    }
    axis.A = hi_a - lo_a;
    axis.E = hi_e - lo_e;
    axis.M = hi_m - lo_m;
    axis.R = r;
    axis.B = b;
    axis.B_mean = b_sum / double(axis.targets.size());
  } else {
    axis.notes.push_back(
        "unidirectional test: no target was approached from both directions "
        "at least " +
        std::to_string(need) +
        " times; A, E, M, R, B are "
        "given per direction only");
  }
  const auto jumps = std::count_if(readings.begin(), readings.end(),
                                   [](const PositionReading& r) { return r.target_setpoint; });
  if (2 * jumps > std::ptrdiff_t(readings.size()))
    axis.notes.push_back(
        "the command is a target setpoint (it jumps to the next target and the axis then "
        "travels there): each reading starts where the measured position comes to rest");
  if (dropped > 0)
    axis.notes.push_back(std::to_string(dropped) + " standstill position(s) with fewer than " +
                         std::to_string(need) +
                         " approaches per direction were not evaluated "
                         "(e.g. overrun or start positions)");
  int fewest = 1 << 30;
  for (const auto& t : axis.targets)
    for (const auto* d : {&t.up, &t.down})
      if (*d) fewest = std::min(fewest, (*d)->runs());
  if (fewest < 5)
    axis.notes.push_back("ISO 230-2 asks for 5 runs per target and direction; the fewest here is " +
                         std::to_string(fewest));
  if (axis.targets.size() < 5)
    axis.notes.push_back("ISO 230-2 asks for at least 5 targets per metre and 5 in all; found " +
                         std::to_string(axis.targets.size()));
  return axis;
}

std::optional<AxisPositioning> evaluate_positioning(const Recording& rec, const std::string& joint,
                                                    const StandstillOptions& o) {
  const auto& cmd = rec.channel(joint + "_cmd");
  const auto* meas = rec.measured(joint);
  if (!meas) rec.channel(joint + "_act");  // throws, naming what the recording has
  auto readings = find_position_readings(rec.t_s, cmd, *meas, o);
  auto result = evaluate_positioning(joint, readings, o);
  if (result)
    result->measured_channel = rec.has(joint + "_meas") ? joint + "_meas" : joint + "_act";
  return result;
}

}  // namespace truecut::analysis
