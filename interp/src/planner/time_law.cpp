#include "time_law.hpp"

#include <algorithm>
#include <cmath>

namespace truecut::interp {

LawState evaluate(const TimeLaw& law, double t) noexcept {
  if (law.phases == 0) return {};
  t = std::clamp(t, 0.0, law.duration_s);
  int k = 0;
  while (k + 1 < law.phases && t > law.phase[k].duration_s) {
    t -= law.phase[k].duration_s;
    ++k;
  }
  const TimeLaw::Phase& p = law.phase[k];
  t = std::min(t, p.duration_s);
  LawState s;
  s.jerk = p.jerk;
  s.a = p.a0 + p.jerk * t;
  s.v = p.v0 + t * (p.a0 + 0.5 * p.jerk * t);
  s.s = p.s0 + t * (p.v0 + t * (0.5 * p.a0 + p.jerk * t / 6.0));
  s.s = std::clamp(s.s, 0.0, law.length);
  s.v = std::max(s.v, 0.0);
  return s;
}

namespace plan {

double change_time_s(double dv, double a, double j) {
  dv = std::abs(dv);
  if (dv <= 0) return 0;
  if (dv * j >= a * a) return dv / a + a / j;
  return 2.0 * std::sqrt(dv / j);
}

double change_distance(double v0, double v1, double a, double j) {
  return 0.5 * (v0 + v1) * change_time_s(v1 - v0, a, j);
}

double reachable_speed(double v0, double length, const LawLimits& lim) {
  if (v0 >= lim.v) return lim.v;
  if (change_distance(v0, lim.v, lim.a, lim.j) <= length) return lim.v;
  double lo = v0, hi = lim.v;
  for (int i = 0; i < 60 && hi - lo > 1e-12 * (1 + hi); ++i) {
    const double mid = 0.5 * (lo + hi);
    (change_distance(v0, mid, lim.a, lim.j) <= length ? lo : hi) = mid;
  }
  return lo;
}

namespace {

// Appends the three phases of a change from v0 to v1.
void add_change(TimeLaw& law, double v0, double v1, const LawLimits& lim) {
  const double dv = std::abs(v1 - v0);
  if (dv <= 0) return;
  const double sign = v1 > v0 ? 1.0 : -1.0;
  double t1, t2;
  if (dv * lim.j >= lim.a * lim.a) {
    t1 = lim.a / lim.j;
    t2 = dv / lim.a - t1;
  } else {
    t1 = std::sqrt(dv / lim.j);
    t2 = 0;
  }
  law.phase[law.phases++].duration_s = t1;
  law.phase[law.phases - 1].jerk = sign * lim.j;
  if (t2 > 0) {
    law.phase[law.phases++].duration_s = t2;
    law.phase[law.phases - 1].jerk = 0;
  }
  law.phase[law.phases++].duration_s = t1;
  law.phase[law.phases - 1].jerk = -sign * lim.j;
}

// Fills in the start state of each phase by exact integration.
void integrate(TimeLaw& law, double v0) {
  double s = 0, v = v0, a = 0, t_total = 0;
  for (int k = 0; k < law.phases; ++k) {
    TimeLaw::Phase& p = law.phase[k];
    p.s0 = s;
    p.v0 = v;
    p.a0 = a;
    const double t = p.duration_s;
    s += t * (v + t * (0.5 * a + p.jerk * t / 6.0));
    v += t * (a + 0.5 * p.jerk * t);
    a += p.jerk * t;
    t_total += t;
  }
  law.duration_s = t_total;
}

}  // namespace

TimeLaw make_law(double length, double v0, double v1, const LawLimits& lim) {
  TimeLaw law;
  law.length = length;
  const double base = std::max(v0, v1);
  double vp = base;
  auto need = [&](double v) {
    return change_distance(v0, v, lim.a, lim.j) + change_distance(v, v1, lim.a, lim.j);
  };
  if (need(lim.v) <= length) {
    vp = std::max(base, lim.v);
  } else {
    double lo = base, hi = std::max(base, lim.v);
    for (int i = 0; i < 60 && hi - lo > 1e-12 * (1 + hi); ++i) {
      const double mid = 0.5 * (lo + hi);
      (need(mid) <= length ? lo : hi) = mid;
    }
    vp = lo;
  }
  add_change(law, v0, vp, lim);
  const double cruise = length - need(vp);
  if (vp > 0 && cruise > 0) {
    law.phase[law.phases++].duration_s = cruise / vp;
    law.phase[law.phases - 1].jerk = 0;
  }
  add_change(law, vp, v1, lim);
  integrate(law, v0);
  return law;
}

TimeLaw make_hold(double duration_s) {
  TimeLaw law;
  law.phases = 1;
  law.phase[0].duration_s = duration_s;
  law.duration_s = duration_s;
  return law;
}

}  // namespace plan
}  // namespace truecut::interp
