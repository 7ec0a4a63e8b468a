#include "truecut/interp/spline.hpp"

#include <algorithm>
#include <cmath>

#include "path.hpp"

namespace truecut::interp {

namespace {

using plan::norm;
using plan::sub;

Vec5 eval_span(const CubicSpan& s, double t) {
  Vec5 p;
  for (int i = 0; i < 5; ++i)
    p[i] = s.c0[i] + t * (s.c1[i] + t * (s.c2[i] + t * s.c3[i]));
  return p;
}

double point_segment_distance(const Vec5& p, const Vec5& a, const Vec5& b) {
  const Vec5 ab = sub(b, a), ap = sub(p, a);
  double dot = 0, len2 = 0;
  for (int i = 0; i < 5; ++i)
    dot += ab[i] * ap[i], len2 += ab[i] * ab[i];
  const double t = len2 > 0 ? std::clamp(dot / len2, 0.0, 1.0) : 0.0;
  Vec5 q;
  for (int i = 0; i < 5; ++i)
    q[i] = a[i] + t * ab[i] - p[i];
  return norm(q);
}

std::vector<CubicSpan> bspline_spans(const std::vector<Vec5>& q) {
  std::vector<CubicSpan> spans;
  const size_t m = q.size() - 1;
  auto at = [&](long i) -> Vec5 {
    if (i < 0) {  // phantom start point: zero curvature, tangent along the first leg
      Vec5 r;
      for (int k = 0; k < 5; ++k)
        r[k] = 2 * q[0][k] - q[1][k];
      return r;
    }
    if (i > static_cast<long>(m)) {
      Vec5 r;
      for (int k = 0; k < 5; ++k)
        r[k] = 2 * q[m][k] - q[m - 1][k];
      return r;
    }
    return q[i];
  };
  for (size_t i = 0; i < m; ++i) {
    const Vec5 p0 = at(long(i) - 1), p1 = at(i), p2 = at(i + 1), p3 = at(i + 2);
    CubicSpan s;
    for (int k = 0; k < 5; ++k) {
      s.c0[k] = (p0[k] + 4 * p1[k] + p2[k]) / 6.0;
      s.c1[k] = (p2[k] - p0[k]) / 2.0;
      s.c2[k] = (p0[k] - 2 * p1[k] + p2[k]) / 2.0;
      s.c3[k] = (-p0[k] + 3 * p1[k] - 3 * p2[k] + p3[k]) / 6.0;
    }
    spans.push_back(s);
  }
  return spans;
}

// Natural cubic spline through the points, chord-length knots.
std::vector<CubicSpan> cspline_spans(const std::vector<Vec5>& x) {
  const size_t m = x.size() - 1;
  std::vector<double> h(m);
  for (size_t i = 0; i < m; ++i)
    h[i] = std::max(norm(sub(x[i + 1], x[i])), 1e-12);
  std::vector<CubicSpan> spans(m);
  for (int k = 0; k < 5; ++k) {
    // Thomas algorithm for the second derivatives M_1..M_{m-1}.
    std::vector<double> M(m + 1, 0.0), cp(m + 1, 0.0), dp(m + 1, 0.0);
    for (size_t i = 1; i < m; ++i) {
      const double a = h[i - 1], b = 2 * (h[i - 1] + h[i]), c = h[i];
      const double r = 6 * ((x[i + 1][k] - x[i][k]) / h[i] - (x[i][k] - x[i - 1][k]) / h[i - 1]);
      const double den = b - a * cp[i - 1];
      cp[i] = c / den;
      dp[i] = (r - a * dp[i - 1]) / den;
    }
    for (size_t i = m - 1; i >= 1; --i)
      M[i] = dp[i] - cp[i] * M[i + 1];
    for (size_t i = 0; i < m; ++i) {
      const double hi = h[i];
      const double slope = (x[i + 1][k] - x[i][k]) / hi - hi * (2 * M[i] + M[i + 1]) / 6.0;
      spans[i].c0[k] = x[i][k];
      spans[i].c1[k] = slope * hi;
      spans[i].c2[k] = M[i] * hi * hi / 2.0;
      spans[i].c3[k] = (M[i + 1] - M[i]) * hi * hi / 6.0;
    }
  }
  return spans;
}

std::vector<CubicSpan> spans_of(SplineMode mode, const std::vector<Vec5>& nodes) {
  if (nodes.size() < 2) return {};
  return mode == SplineMode::kCspline ? cspline_spans(nodes) : bspline_spans(nodes);
}

double sin_turn(const Vec5& a, const Vec5& b, const Vec5& c) {
  const Vec5 u = sub(b, a), v = sub(c, b);
  const double nu = norm(u), nv = norm(v);
  if (nu <= 0 || nv <= 0) return 0;
  double dot = 0;
  for (int i = 0; i < 5; ++i)
    dot += u[i] * v[i];
  const double cs = std::clamp(dot / (nu * nv), -1.0, 1.0);
  return std::sqrt(std::max(0.0, 1 - cs * cs));
}

Vec5 along(const Vec5& from, const Vec5& to, double dist) {
  const Vec5 d = sub(to, from);
  const double n = norm(d);
  Vec5 r;
  for (int i = 0; i < 5; ++i)
    r[i] = from[i] + d[i] * dist / n;
  return r;
}

// Bspline: two nodes at d2 = k * 2 Er / sin(beta) around every control point
// where that is shorter than the legs.
std::vector<Vec5> bspline_nodes(const std::vector<Vec5>& p, double tol, double k) {
  std::vector<Vec5> out{p.front()};
  for (size_t i = 1; i + 1 < p.size(); ++i) {
    const double sb = sin_turn(p[i - 1], p[i], p[i + 1]);
    const double leg_in = norm(sub(p[i], p[i - 1])), leg_out = norm(sub(p[i + 1], p[i]));
    const double d2 = sb > 0 ? k * 2.0 * tol / sb : 1e300;
    if (d2 < 0.45 * std::min(leg_in, leg_out)) {
      out.push_back(along(p[i], p[i - 1], d2));
      out.push_back(p[i]);
      out.push_back(along(p[i], p[i + 1], d2));
    } else {
      out.push_back(p[i]);
    }
  }
  out.push_back(p.back());
  return out;
}

// Cspline: nodes at constant length (at most `step`) along every leg.
std::vector<Vec5> cspline_nodes(const std::vector<Vec5>& p, double step) {
  std::vector<Vec5> out{p.front()};
  for (size_t i = 1; i < p.size(); ++i) {
    const Vec5 d = sub(p[i], p[i - 1]);
    const int n = std::max(1, static_cast<int>(std::ceil(norm(d) / step - 1e-9)));
    for (int j = 1; j <= n; ++j) {
      Vec5 q;
      for (int k = 0; k < 5; ++k)
        q[k] = p[i - 1][k] + d[k] * j / n;
      out.push_back(j == n ? p[i] : q);
    }
  }
  return out;
}

}  // namespace

double contour_error_mm(const std::vector<CubicSpan>& spans, const std::vector<Vec5>& points) {
  if (points.size() < 2) return 0;
  const long last_seg = static_cast<long>(points.size()) - 2;
  long near = 0;
  double worst = 0;
  constexpr int kSamples = 32;
  for (const CubicSpan& s : spans) {
    for (int j = 0; j <= kSamples; ++j) {
      const Vec5 q = eval_span(s, double(j) / kSamples);
      double best = 1e300;
      long best_i = near;
      // The curve advances along the polyline: search around the last match.
      for (long i = std::max(0L, near - 8); i <= std::min(last_seg, near + 8); ++i) {
        const double d = point_segment_distance(q, points[i], points[i + 1]);
        if (d < best) best = d, best_i = i;
      }
      near = best_i;
      worst = std::max(worst, best);
    }
  }
  return worst;
}

SplineFit fit_spline(SplineMode mode, const std::vector<Vec5>& points) {
  SplineFit f;
  f.nodes = points;
  f.spans = spans_of(mode, points);
  f.error_mm = contour_error_mm(f.spans, points);
  return f;
}

SplineFit fit_spline_within(SplineMode mode, const std::vector<Vec5>& points, double tol,
                            SplineReport* report) {
  SplineFit best = fit_spline(mode, points);
  const double before = best.error_mm;
  if (before > tol && points.size() > 2) {
    if (mode == SplineMode::kBspline) {
      for (double k = 1.0; k > 1e-3 && best.error_mm > tol; k *= 0.5) {
        SplineFit f;
        f.nodes = bspline_nodes(points, tol, k);
        f.spans = spans_of(mode, f.nodes);
        f.error_mm = contour_error_mm(f.spans, points);
        best = f;
      }
    } else {
      double longest = 0;
      for (size_t i = 1; i < points.size(); ++i)
        longest = std::max(longest, norm(sub(points[i], points[i - 1])));
      for (double step = 0.7 * longest; best.error_mm > tol && step > 1e-4; step *= 0.7) {
        SplineFit f;
        f.nodes = cspline_nodes(points, step);
        if (f.nodes.size() > 200000) break;
        f.spans = spans_of(mode, f.nodes);
        f.error_mm = contour_error_mm(f.spans, points);
        best = f;
      }
    }
  }
  if (report) {
    report->mode = mode;
    report->points = static_cast<int>(points.size());
    report->nodes_inserted = static_cast<int>(best.nodes.size() - points.size());
    report->tolerance_mm = tol;
    report->error_before_mm = before;
    report->error_after_mm = best.error_mm;
  }
  return best;
}

}  // namespace truecut::interp
