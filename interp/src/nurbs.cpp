#include "truecut/interp/nurbs.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <span>
#include <stdexcept>

namespace truecut::interp {

namespace {

// Knot j of n + 1 points of order k: k zeros, 1 ... n-k+1, k times n-k+2.
double knot(int j, int n, int k) {
  if (j < k) return 0;
  if (j > n) return n - k + 2;
  return j - k + 1;
}

double distance_to_chord(const NurbsPoint2& p, const NurbsPoint2& a, const NurbsPoint2& b) {
  const double dx = b[0] - a[0], dy = b[1] - a[1];
  const double len2 = dx * dx + dy * dy;
  double t = len2 > 0 ? ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2 : 0;
  t = std::clamp(t, 0.0, 1.0);
  return std::hypot(p[0] - a[0] - t * dx, p[1] - a[1] - t * dy);
}

struct Refiner {
  const NurbsFeed& nurbs;
  double tolerance;
  std::vector<NurbsPoint2>& out;

  void chord(double u0, const NurbsPoint2& p0, double u1, const NurbsPoint2& p1, int depth) {
    bool split = false;
    if (depth < 17) {
      for (double f : {0.25, 0.5, 0.75})
        if (distance_to_chord(nurbs_point(nurbs, u0 + f * (u1 - u0)), p0, p1) > tolerance) {
          split = true;
          break;
        }
    }
    if (!split) {
      out.push_back(p1);
      return;
    }
    const double um = 0.5 * (u0 + u1);
    const NurbsPoint2 pm = nurbs_point(nurbs, um);
    chord(u0, p0, um, pm, depth + 1);
    chord(um, pm, u1, p1, depth + 1);
  }
};

}  // namespace

double nurbs_parameter_end(const NurbsFeed& nurbs) {
  const int n = static_cast<int>(nurbs.points.size()) - 1;
  return n - nurbs.order + 2;
}

NurbsPoint2 nurbs_point(const NurbsFeed& nurbs, double u) {
  const int count = static_cast<int>(nurbs.points.size());
  const int n = count - 1, k = nurbs.order;
  if (k < 2 || count < k)
    throw std::invalid_argument("NURBS with fewer control points than its order");
  const double end = nurbs_parameter_end(nurbs);
  if (!(u > 0)) return {nurbs.points.front().x, nurbs.points.front().y};
  if (u >= end) return {nurbs.points.back().x, nurbs.points.back().y};
  // The span [knot(s), knot(s+1)) holding u: s = k-1 + floor(u).
  const int s = std::min(k - 1 + static_cast<int>(std::floor(u)), n);
  // Cox-de Boor: the k basis functions of order k that are non-zero there,
  // for points s-k+1 ... s.
  // On the stack for the orders programs use (G5 4, G5.1 3, G5.2 L): the
  // polyline of one curve evaluates it hundreds of thousands of times.
  constexpr int kStackOrder = 16;
  std::array<double, 3 * kStackOrder> small{};
  std::vector<double> large;
  double* scratch = small.data();
  if (k > kStackOrder) {
    large.assign(3 * static_cast<size_t>(k), 0.0);
    scratch = large.data();
  }
  const std::span<double> basis(scratch, static_cast<size_t>(k)),
      left(scratch + k, static_cast<size_t>(k)), right(scratch + 2 * k, static_cast<size_t>(k));
  basis[0] = 1;
  for (int j = 1; j < k; ++j) {
    left[static_cast<size_t>(j)] = u - knot(s + 1 - j, n, k);
    right[static_cast<size_t>(j)] = knot(s + j, n, k) - u;
    double saved = 0;
    for (int r = 0; r < j; ++r) {
      const double denom = right[static_cast<size_t>(r + 1)] + left[static_cast<size_t>(j - r)];
      const double t = denom != 0 ? basis[static_cast<size_t>(r)] / denom : 0;
      basis[static_cast<size_t>(r)] = saved + right[static_cast<size_t>(r + 1)] * t;
      saved = left[static_cast<size_t>(j - r)] * t;
    }
    basis[static_cast<size_t>(j)] = saved;
  }
  double x = 0, y = 0, w = 0;
  for (int r = 0; r < k; ++r) {
    const NurbsControlPoint& p = nurbs.points[static_cast<size_t>(s - k + 1 + r)];
    const double b = basis[static_cast<size_t>(r)] * p.weight;
    x += b * p.x;
    y += b * p.y;
    w += b;
  }
  return {x / w, y / w};
}

std::vector<NurbsPoint2> nurbs_polyline(const NurbsFeed& nurbs, double tolerance) {
  if (!(tolerance > 0)) throw std::invalid_argument("NURBS chord tolerance must be positive");
  std::vector<NurbsPoint2> out;
  const int spans = static_cast<int>(std::lround(nurbs_parameter_end(nurbs)));
  Refiner r{nurbs, tolerance, out};
  constexpr int kStartChords = 8;
  NurbsPoint2 p0 = nurbs_point(nurbs, 0);
  for (int i = 0; i < spans * kStartChords; ++i) {
    const double u0 = static_cast<double>(i) / kStartChords;
    const double u1 = static_cast<double>(i + 1) / kStartChords;
    const NurbsPoint2 p1 = nurbs_point(nurbs, u1);
    r.chord(u0, p0, u1, p1, 0);
    p0 = p1;
  }
  if (out.empty()) out.push_back({nurbs.points.back().x, nurbs.points.back().y});
  out.back() = {nurbs.points.back().x, nurbs.points.back().y};
  return out;
}

}  // namespace truecut::interp
