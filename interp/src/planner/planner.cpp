#include "truecut/interp/planner.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "limits.hpp"
#include "path.hpp"
#include "time_law.hpp"

namespace truecut::interp {

namespace {

using namespace plan;

constexpr double kCrawl_mm_per_s = 0.1;

struct Stretch {
  int move = 0;
  double u0 = 0, u1 = 0;
  LawLimits lim;
};

void check(const PlannerOptions& o) {
  for (const AxisLimits& a : o.limits.axis)
    if (!(a.max_velocity > 0 && a.max_acceleration > 0 && a.max_jerk > 0))
      throw std::invalid_argument("planner: every axis limit must be positive");
  if (!(o.servo_period_s > 0)) throw std::invalid_argument("planner: servo period must be > 0");
  if (!(o.rotary_weight_mm_per_deg > 0))
    throw std::invalid_argument("planner: rotary weight must be > 0");
}

bool stops_after(const Move& m) {
  return m.dwell || m.stop_after || m.mode == PathMode::kExactStop;
}

}  // namespace

Plan plan_program(const CanonProgram& program, const PlannerOptions& opt) {
  check(opt);
  const double w = opt.rotary_weight_mm_per_deg;
  Path path = build_path(program, opt);
  Plan out;
  out.operations = path.operations;
  out.splines = path.splines;
  out.stats.moves = path.programmed_moves;
  out.stats.blends = insert_blends(path.moves, opt);
  const std::vector<Move>& moves = path.moves;

  // Stretches of path with their limits, and a speed cap per junction
  // (caps[k] is the junction before stretch k; the last one ends the plan).
  std::vector<Stretch> st;
  std::vector<double> caps;
  for (size_t i = 0; i < moves.size(); ++i) {
    const Move& m = moves[i];
    const int n = m.dwell ? 1 : stretches(m, w);
    for (int s = 0; s < n; ++s) {
      Stretch x;
      x.move = static_cast<int>(i);
      x.u0 = m.piece.length * s / n;
      x.u1 = s + 1 == n ? m.piece.length : m.piece.length * (s + 1) / n;
      if (!m.dwell) x.lim = law_limits(m, derivative_bounds(m, x.u0, x.u1, w), opt.limits);
      double cap = 0;
      if (!st.empty() && !m.dwell) {
        const Stretch& prev = st.back();
        const Move& pm = moves[prev.move];
        cap = std::min(prev.lim.v, x.lim.v);
        if (s == 0) {
          if (stops_after(pm) || pm.tcp != m.tcp)
            cap = 0;
          else
            cap = std::min(cap, junction_cap(pm, m, opt.limits, opt.servo_period_s, w));
        }
      }
      // A corner that may only be passed at a crawl is a stop (as G61 users expect).
      if (cap < kCrawl_mm_per_s) cap = 0;
      caps.push_back(cap);
      st.push_back(x);
    }
  }
  caps.push_back(0.0);

  // Look-ahead: backward then forward, so that every stretch can reach its
  // exit speed from its entry speed.
  const size_t n = st.size();
  std::vector<double> v(caps);
  for (size_t k = n; k-- > 0;)
    if (!moves[st[k].move].dwell)
      v[k] = std::min(v[k], reachable_speed(v[k + 1], st[k].u1 - st[k].u0, st[k].lim));
  for (size_t k = 0; k < n; ++k)
    if (!moves[st[k].move].dwell)
      v[k + 1] = std::min(v[k + 1], reachable_speed(v[k], st[k].u1 - st[k].u0, st[k].lim));

  out.segments.reserve(n + 1);
  for (size_t k = 0; k < n; ++k) {
    const Move& m = moves[st[k].move];
    PlanSegment seg;
    seg.tcp = m.tcp;
    seg.rapid = m.rapid;
    seg.piece = m.piece;
    seg.u0 = st[k].u0;
    seg.rotary_weight_mm_per_deg = w;
    seg.kinematics = m.kinematics;
    seg.line = m.line;
    seg.tool = m.tool;
    seg.operation = m.operation;
    seg.programmed_feed_mm_per_s = m.programmed_feed_mm_per_s;
    seg.spindle_rpm = m.spindle_rpm;
    if (m.dwell) {
      seg.kind = SegmentKind::kDwell;
      seg.law = make_hold(m.dwell_s);
    } else {
      seg.law = make_law(st[k].u1 - st[k].u0, v[k], v[k + 1], st[k].lim);
    }
    if (k > 0 && v[k] == 0) ++out.stats.exact_stops;
    out.stats.duration_s += seg.law.duration_s;
    out.stats.length_mm += seg.law.length;
    out.segments.push_back(seg);
  }
  if (out.segments.empty()) {
    PlanSegment hold;
    hold.kind = SegmentKind::kDwell;
    hold.rotary_weight_mm_per_deg = w;
    hold.kinematics = opt.kinematics;
    out.segments.push_back(hold);
  }
  out.segments.back().last = true;
  return out;
}

}  // namespace truecut::interp
