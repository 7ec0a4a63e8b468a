#include "spline_piece.hpp"

#include <cmath>

namespace truecut::interp::plan {

namespace {

Vec5 d1(const CubicSpan& s, double t) {
  Vec5 d;
  for (int i = 0; i < 5; ++i)
    d[i] = s.c1[i] + t * (2 * s.c2[i] + 3 * t * s.c3[i]);
  return d;
}

Vec5 d2(const CubicSpan& s, double t) {
  Vec5 d;
  for (int i = 0; i < 5; ++i)
    d[i] = 2 * s.c2[i] + 6 * t * s.c3[i];
  return d;
}

double dot(const Vec5& a, const Vec5& b) {
  double r = 0;
  for (int i = 0; i < 5; ++i)
    r += a[i] * b[i];
  return r;
}

double speed(const CubicSpan& s, double t) {
  return std::sqrt(dot(d1(s, t), d1(s, t)));
}

// Of the inverse arc-length map t(s): dt/ds = 1/|P'| and
// d2t/ds2 = -(P'.P'')/|P'|^4.
double slope(const CubicSpan& s, double t) {
  return 1.0 / speed(s, t);
}
double bend(const CubicSpan& s, double t) {
  const double v = speed(s, t);
  return -dot(d1(s, t), d2(s, t)) / (v * v * v * v);
}

}  // namespace

bool cubic_piece(const CubicSpan& span, PathPiece& p) {
  // Arc length by composite Simpson over 32 intervals.
  constexpr int n = 32;
  double len = speed(span, 0) + speed(span, 1);
  for (int i = 1; i < n; ++i)
    len += (i % 2 ? 4 : 2) * speed(span, double(i) / n);
  len /= 3.0 * n;
  if (len < 1e-9) return false;
  p = PathPiece{};
  p.kind = PathPiece::kCubic;
  p.length = len;
  p.a = span.c0;
  p.b = span.c1;
  p.c = span.c2;
  p.d = span.c3;
  // t(u) quintic matching value, slope and bend of the true map at both ends.
  p.m1 = 1.0 / len;
  const double v0 = speed(span, 0), v1 = speed(span, 1);
  if (v0 > 1e-12 && v1 > 1e-12) {
    const double L = len, m1 = slope(span, 0), m2 = 0.5 * bend(span, 0);
    const double r0 = 1.0 - (m1 * L + m2 * L * L);
    const double r1 = (slope(span, 1) - (m1 + 2 * m2 * L)) * L;
    const double r2 = (bend(span, 1) - 2 * m2) * L * L;
    const double x = 10 * r0 - 4 * r1 + 0.5 * r2;
    const double y = -15 * r0 + 7 * r1 - r2;
    const double z = 6 * r0 - 3 * r1 + 0.5 * r2;
    const double m3 = x / (L * L * L), m4 = y / (L * L * L * L), m5 = z / (L * L * L * L * L);
    bool monotone = true;
    for (int i = 0; i <= 32 && monotone; ++i) {
      const double u = L * i / 32.0;
      monotone = m1 + u * (2 * m2 + u * (3 * m3 + u * (4 * m4 + u * 5 * m5))) > 0;
    }
    if (monotone) p.m1 = m1, p.m2 = m2, p.m3 = m3, p.m4 = m4, p.m5 = m5;
  }
  return true;
}

}  // namespace truecut::interp::plan
