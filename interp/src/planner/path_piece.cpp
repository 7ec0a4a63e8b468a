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

}  // namespace truecut::interp
