#include <cmath>

#include "truecut/interp/plan_segment.hpp"

namespace truecut::interp {

Vec5 evaluate(const PathPiece& p, double u) noexcept {
  Vec5 out{};
  switch (p.kind) {
    case PathPiece::kLine:
      for (int i = 0; i < 5; ++i)
        out[i] = p.a[i] + u * p.b[i];
      break;
    case PathPiece::kArc: {
      const double f = p.length > 0 ? u / p.length : 0.0;
      const double th = p.sweep_rad * f;
      const double r = p.radius + (p.radius_end - p.radius) * f;
      const double cs = r * std::cos(th), sn = r * std::sin(th);
      for (int i = 0; i < 5; ++i)
        out[i] = p.a[i] + cs * p.b[i] + sn * p.c[i] + th * p.d[i];
      break;
    }
    case PathPiece::kCubic: {
      const double t = u * (p.m1 + u * (p.m2 + u * (p.m3 + u * (p.m4 + u * p.m5))));
      for (int i = 0; i < 5; ++i)
        out[i] = p.a[i] + t * (p.b[i] + t * (p.c[i] + t * p.d[i]));
      break;
    }
  }
  return out;
}

Vec5 evaluate_near(const PathPiece& p, double u, double du) noexcept {
  if (p.kind != PathPiece::kArc || p.length <= 0) return evaluate(p, u + du);
  const double f = u / p.length, df = du / p.length;
  const double th = p.sweep_rad * f, dth = p.sweep_rad * df;
  const double r = p.radius + (p.radius_end - p.radius) * f + (p.radius_end - p.radius) * df;
  const double c0 = std::cos(th), s0 = std::sin(th), c1 = std::cos(dth), s1 = std::sin(dth);
  const double cs = r * (c0 * c1 - s0 * s1), sn = r * (s0 * c1 + c0 * s1);
  Vec5 out{};
  for (int i = 0; i < 5; ++i)
    out[i] = p.a[i] + cs * p.b[i] + sn * p.c[i] + (th * p.d[i] + dth * p.d[i]);
  return out;
}

}  // namespace truecut::interp
