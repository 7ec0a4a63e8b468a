// Where a line meets the cutter's solid (internal to the cutting library).
//
// The solid is the set of points within corner radius rc of the "core" disk
// cylinder (radius ρ = R − rc, from rc to L up the axis), cut flat at the
// flute length L: a cylinder of radius R for w ∈ [rc, L] on top of the
// rounded bottom {w ∈ [0, rc], dist(x, disk(ρ) at w = rc) ≤ rc}. Flat end
// mill: rc = 0 (no bottom part); ball: ρ = 0 (the bottom is a half sphere).
// The solid is convex, so a line meets it in one interval.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>

namespace truecut::sim::cutting::detail {

constexpr double kInf = std::numeric_limits<double>::infinity();

struct Span {
  double t0 = kInf;
  double t1 = -kInf;
  bool empty() const { return !(t0 <= t1); }
};

inline Span intersect(Span a, Span b) {
  return {std::max(a.t0, b.t0), std::min(a.t1, b.t1)};
}
inline Span hull(Span a, Span b) {
  if (a.empty()) return b;
  if (b.empty()) return a;
  return {std::min(a.t0, b.t0), std::max(a.t1, b.t1)};
}

// {t : A t² + B t + C ≤ 0} for A ≥ 0.
inline Span quadratic_span(double a, double b, double c) {
  if (a < 1e-24) return c <= 0 ? Span{-kInf, kInf} : Span{};
  const double disc = b * b - 4 * a * c;
  if (disc < 0) return {};
  const double q = -0.5 * (b + std::copysign(std::sqrt(disc), b));
  if (q == 0) return {0, 0};
  const double r1 = q / a, r2 = c / q;
  return {std::min(r1, r2), std::max(r1, r2)};
}

// {t : w_lo ≤ qa + t·na ≤ w_hi}.
inline Span slab_span(double qa, double na, double w_lo, double w_hi) {
  if (std::abs(na) < 1e-15) return (qa >= w_lo && qa <= w_hi) ? Span{-kInf, kInf} : Span{};
  double ta = (w_lo - qa) / na, tb = (w_hi - qa) / na;
  if (ta > tb) std::swap(ta, tb);
  return {ta, tb};
}

struct ToolGeometry {
  double radius_mm;
  double corner_mm;
  double core_mm;  // ρ = R − rc
  double flute_mm;
};

// Distance from y (relative to the disk centre) to the disk of radius rho
// with normal a, and its derivative along n.
inline double disk_distance(const Eigen::Vector3d& y, const Eigen::Vector3d& a, double rho,
                            const Eigen::Vector3d& n, double& slope) {
  const double ya = y.dot(a);
  const Eigen::Vector3d yr_vec = y - ya * a;
  const double yr = yr_vec.norm();
  if (yr <= rho) {
    slope = (ya >= 0 ? 1.0 : -1.0) * a.dot(n);
    return std::abs(ya);
  }
  const Eigen::Vector3d diff = y - (rho / yr) * yr_vec;
  const double d = diff.norm();
  slope = d > 0 ? diff.dot(n) / d : 0.0;
  return d;
}

// The bull-nose bottom within [s0, s1] (a bracket inside [lo, hi] of the
// dexel): g(t) = dist(x(t), disk) − rc is convex and C¹ where g = 0, so the
// entry is found by safeguarded Newton from the left. The exit is only
// needed as "beyond the entry", so the bracket end stands in for it.
inline Span torus_span(const Eigen::Vector3d& qc, const Eigen::Vector3d& n,
                       const Eigen::Vector3d& a, const ToolGeometry& g, double s0, double s1) {
  double slope = 0;
  auto f = [&](double t) {
    return disk_distance(qc + t * n, a, g.core_mm, n, slope) - g.corner_mm;
  };
  const double f0 = f(s0);
  const double slope0 = slope;
  if (f0 <= 0) return {s0, s1};
  const double f1 = f(s1);
  if (f1 > 0) {
    // Both ends outside: a zero set strictly inside needs the minimum there.
    if (slope0 >= 0 || slope <= 0) return {};
    constexpr double kGolden = 0.6180339887498949;
    double lo = s0, hi = s1;
    double x1 = hi - kGolden * (hi - lo), x2 = lo + kGolden * (hi - lo);
    double v1 = f(x1), v2 = f(x2);
    for (int it = 0; it < 80 && v1 > 0 && v2 > 0; ++it) {
      if (v1 < v2) {
        hi = x2, x2 = x1, v2 = v1, x1 = hi - kGolden * (hi - lo), v1 = f(x1);
      } else {
        lo = x1, x1 = x2, v1 = v2, x2 = lo + kGolden * (hi - lo), v2 = f(x2);
      }
    }
    if (v1 > 0 && v2 > 0) return {};
    s1 = v1 <= 0 ? x1 : x2;  // inside: the entry lies in [s0, s1]
  }
  // Root of the convex g in (s0, s1]: Newton from the outside, bisection
  // when a step would leave the bracket.
  double lo = s0, hi = s1, ft = f0, st = slope0;
  for (int it = 0; it < 60 && hi - lo > 1e-12; ++it) {
    double next = st < 0 ? lo - ft / st : 0.5 * (lo + hi);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const double fn = f(next);
    if (fn > 0) {
      lo = next, ft = fn, st = slope;
      if (fn < 1e-13) return {lo, s1};  // on the surface to 1e-13 mm
    } else {
      hi = next;
    }
  }
  return {hi, s1};
}

// The interval of the line q + t·n (q relative to the tip, n unit) inside the
// tool with unit axis a, as far as it matters for a dexel holding material on
// [lo, hi]: the bull-nose bottom is only resolved inside [lo, hi] (with the
// entry exact and the exit clipped), which gives the same cut.
inline Span tool_span(const Eigen::Vector3d& q, const Eigen::Vector3d& n, const Eigen::Vector3d& a,
                      const ToolGeometry& g, double lo, double hi) {
  const double qa = q.dot(a), na = n.dot(a);
  const Eigen::Vector3d qp = q - qa * a, np = n - na * a;
  const double ap = np.squaredNorm(), bp = 2 * qp.dot(np), cp = qp.squaredNorm();
  const double r2 = g.radius_mm * g.radius_mm;
  // Cylinder of radius R between rc and L.
  Span side = quadratic_span(ap, bp, cp - r2);
  if (side.empty()) return {};  // the whole tool lies inside this cylinder
  Span top = intersect(side, slab_span(qa, na, g.corner_mm, g.flute_mm));
  if (g.corner_mm <= 0) return top;
  Span bottom;
  if (g.core_mm <= 0) {  // ball: sphere of radius rc about rc·a, below w = rc
    const Eigen::Vector3d qc = q - g.corner_mm * a;
    bottom = intersect(quadratic_span(n.squaredNorm(), 2 * qc.dot(n),
                                      qc.squaredNorm() - g.corner_mm * g.corner_mm),
                       slab_span(qa, na, -kInf, g.corner_mm));
  } else {
    const Span range = intersect(side, slab_span(qa, na, 0, g.corner_mm));
    // Only the part inside the dexel's [lo, hi] can change the cut.
    const double s0 = std::max(range.t0, lo), s1 = std::min(range.t1, hi);
    if (!range.empty() && s0 <= s1) bottom = torus_span(q - g.corner_mm * a, n, a, g, s0, s1);
  }
  return hull(top, bottom);
}

// A quick test, without square roots or divisions, that tool_span(q, n, a, g,
// lo, h) starts at or above h, i.e. that the tool does not reach below the
// material's top h on this line — true for most dexels under a tool that
// moved a little since the last instance (their material already ends at or
// below its surface). True only where each part of the solid is entered
// beyond h by a margin (1e-8 mm, mm²) far above the rounding of tool_span's
// roots, so it never hides a cut that tool_span would make: a cut dexel gets
// the same height bit for bit, with or without this test.
[[gnu::always_inline]] inline bool starts_above(const Eigen::Vector3d& q, const Eigen::Vector3d& n,
                                                const Eigen::Vector3d& a, const ToolGeometry& g,
                                                double h) {
  constexpr double m = 1e-8;
  const double qa = q.dot(a), na = n.dot(a);
  const double wh = qa + h * na;  // height along the axis of the line's point at h
  // The line climbs along the axis into the slab [w_lo, ...] beyond h, or
  // descends into [..., w_hi] beyond h.
  auto enters_slab_above = [&](double w_lo, double w_hi) {
    return (wh < w_lo - m && na > m) || (wh > w_hi + m && na < -m);
  };
  // The line is outside the cylinder of radius R at h and closing in.
  auto enters_cylinder_above = [&] {
    const Eigen::Vector3d qp = q - qa * a, np = n - na * a;
    const Eigen::Vector3d v = qp + h * np;
    return v.squaredNorm() - g.radius_mm * g.radius_mm > m && v.dot(np) < -m;
  };
  // The cylinder part, w in [rc, L].
  if (!enters_slab_above(g.corner_mm, g.flute_mm) && !enters_cylinder_above()) return false;
  if (g.corner_mm <= 0) return true;  // flat end mill: nothing below
  if (g.core_mm <= 0) {               // ball: the sphere about rc·a, below w = rc
    const Eigen::Vector3d v = q - g.corner_mm * a + h * n;
    if (v.squaredNorm() - g.corner_mm * g.corner_mm > m && v.dot(n) < -m) return true;
    return wh > g.corner_mm + m && na < -m;
  }
  // bull-nose: its bottom lies within the cylinder, w in [0, rc]
  return enters_slab_above(0, g.corner_mm) || enters_cylinder_above();
}

// True only when the box [lo, hi] holds no point of the tool (tip at the
// origin, unit axis a), with a margin (1e-6 mm) far above the rounding of
// tool_span's roots: a line inside the box then gets no cut from tool_span.
// Conservative: the tool is taken as the cylinder of radius R from w = rc
// (w = 0 unless a ball) to L, plus a ball's whole sphere; the box is
// separated from the cylinder along the axis, or along the direction from
// the axis to the box's centre (a separating axis, square to the tool's).
inline bool box_misses_tool(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                            const Eigen::Vector3d& a, const ToolGeometry& g) {
  constexpr double m = 1e-6;
  const bool ball = g.core_mm <= 0 && g.corner_mm > 0;
  if (ball) {  // the sphere of radius rc about rc·a
    const Eigen::Vector3d s = g.corner_mm * a;
    const Eigen::Vector3d out = (lo - s).cwiseMax(s - hi).cwiseMax(0.0);
    if (out.squaredNorm() <= (g.corner_mm + m) * (g.corner_mm + m)) return false;
  }
  const Eigen::Vector3d c = 0.5 * (lo + hi), e = 0.5 * (hi - lo);
  const double ca = c.dot(a);
  const double half_a = e.dot(a.cwiseAbs());  // the box's half extent along a
  const double w0 = ball ? g.corner_mm : 0.0;
  if (ca + half_a < w0 - m || ca - half_a > g.flute_mm + m) return true;
  // Along u, the unit direction from the axis to the centre, square to a: the
  // cylinder spans [−R, R], the box its centre's distance ± Σ e_i |u_i|.
  const Eigen::Vector3d across = c - ca * a;
  const double d = across.norm();
  if (d <= g.radius_mm + m) return false;
  return d - e.dot(across.cwiseAbs()) / d > g.radius_mm + m;
}

}  // namespace truecut::sim::cutting::detail
