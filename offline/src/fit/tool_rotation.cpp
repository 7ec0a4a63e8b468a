// Tool rotation from the compensation vectors along a flank
// (tool_rotation.hpp).
#include "truecut/offline/tool_rotation.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numeric>

#include <boost/math/distributions/normal.hpp>
#include <boost/math/distributions/students_t.hpp>

#include "truecut/rt/core/joint_mode.hpp"

namespace truecut::offline {

namespace {

// Standard error of the slope b of the line s = a + b h fitted through
// (h, s), with the residuals' serial correlation taken in: a scan's error
// is correlated over the size of its mesh's facets, so neighbouring points
// along the flank do not count as independent. Lag-1 autocorrelation rho of
// the residuals in order of h, n_eff = n (1 - rho) / (1 + rho) (AR(1)), and
// var(b) = s^2 / Sxx * n / n_eff.
struct SlopeError {
  double standard_error = 0.0;
  double n_eff = 0.0;
};
SlopeError slope_standard_error(std::vector<std::pair<double, double>>& hs, double a, double b,
                                double sxx) {
  std::sort(hs.begin(), hs.end());
  const auto n = static_cast<double>(hs.size());
  double rss = 0.0, lag = 0.0, prev = 0.0;
  for (std::size_t i = 0; i < hs.size(); ++i) {
    const double r = hs[i].second - (a + b * hs[i].first);
    rss += r * r;
    if (i > 0) lag += r * prev;
    prev = r;
  }
  if (!(rss > 0.0) || hs.size() < 3) return {};
  const double rho = std::clamp(lag / rss, 0.0, 0.99);
  const double n_eff = std::max(1.0, n * (1.0 - rho) / (1.0 + rho));
  const double s2 = rss / (n - 2.0);
  return {std::sqrt(s2 / sxx * n / n_eff), n_eff};
}

// |b| / se that a slope must reach: the two-sided quantile of Student's t
// with n_eff - 2 degrees of freedom (at least 1) at the level that z
// standard errors give under a normal law (z = 3: 0.27 %). With few
// effective points the standard error is itself uncertain and t's tails
// are heavy.
double slope_threshold(double z, double n_eff) {
  if (!(z > 0.0)) return 0.0;
  const double tail = boost::math::cdf(boost::math::complement(boost::math::normal(), z));
  const boost::math::students_t t(std::max(n_eff - 2.0, 1.0));
  return boost::math::quantile(boost::math::complement(t, tail));
}

}  // namespace

Eigen::Vector3d realisable_rotation(const Eigen::Vector3d& w_rad, const Eigen::Vector3d& axis,
                                    double c_deg, RotaryKinematics kinematics) {
  const Eigen::Vector3d k = axis.normalized();
  if (kinematics == RotaryKinematics::kAnyOrientation) return w_rad - w_rad.dot(k) * k;
  const double sin_a = std::hypot(k.x(), k.y());
  // (sin C, cos C): from the axis where A has tilted it, else the C word.
  double sin_c = std::sin(c_deg * M_PI / 180.0), cos_c = std::cos(c_deg * M_PI / 180.0);
  if (sin_a > 1e-12) {
    sin_c = k.x() / sin_a;
    cos_c = k.y() / sin_a;
  }
  const Eigen::Vector3d along_a(k.z() * sin_c, k.z() * cos_c, -sin_a);  // d k / dA, unit
  const Eigen::Vector3d along_c(cos_c, -sin_c, 0.0);                    // d k / dC / sin A
  const Eigen::Vector3d dk = w_rad.cross(k);
  Eigen::Vector3d kept = dk.dot(along_a) * along_a;
  if (sin_a >= rt::comp::kRotaryDampingStart) kept += dk.dot(along_c) * along_c;
  return k.cross(kept);
}

ToolRotationEstimate estimate_tool_rotation(std::span<const PlacedVector> placed,
                                            const ToolRotationOptions& options) {
  ToolRotationEstimate out;
  out.translations_mm.resize(placed.size());
  std::vector<std::size_t> order(placed.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return placed[a].sample < placed[b].sample;
  });
  const double cos_spread = std::cos(options.max_normal_spread_deg * M_PI / 180.0);
  // Each point's height above its tip along the axis.
  std::vector<double> height(placed.size());
  for (std::size_t i = 0; i < placed.size(); ++i)
    height[i] = (placed[i].point_mm - placed[i].tcp_mm).dot(placed[i].axis);
  for (std::size_t begin = 0; begin < order.size();) {
    std::size_t end = begin;
    while (end < order.size() && placed[order[end]].sample == placed[order[begin]].sample)
      ++end;
    const PlacedVector& first = placed[order[begin]];
    const Eigen::Vector3d k = first.axis;
    // The group's normal across the axis.
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    double h_min = 1e300, h_max = -1e300;
    for (std::size_t i = begin; i < end; ++i) {
      const PlacedVector& p = placed[order[i]];
      n += p.normal;
      const double h = height[order[i]];
      h_min = std::min(h_min, h);
      h_max = std::max(h_max, h);
    }
    n -= n.dot(k) * k;
    Eigen::Vector3d w = Eigen::Vector3d::Zero();
    const auto count = static_cast<int>(end - begin);
    if (n.norm() > 1e-9 && count >= options.min_points &&
        h_max - h_min >= options.min_height_spread_mm) {
      n.normalize();
      bool one_way = true;
      for (std::size_t i = begin; i < end; ++i)
        one_way = one_way && placed[order[i]].normal.dot(n) >= cos_spread;
      if (one_way) {
        // Least-squares line s = a + b h through the normal components.
        double sh = 0, ss = 0, shh = 0, shs = 0;
        std::vector<std::pair<double, double>> hs;
        hs.reserve(end - begin);
        for (std::size_t i = begin; i < end; ++i) {
          const PlacedVector& p = placed[order[i]];
          const double h = height[order[i]], s = p.vector_mm.dot(n);
          sh += h;
          ss += s;
          shh += h * h;
          shs += h * s;
          hs.emplace_back(h, s);
        }
        const double m = count, var = shh - sh * sh / m;
        const double b = var > 0.0 ? (shs - sh * ss / m) / var : 0.0;
        const SlopeError se =
            var > 0.0 ? slope_standard_error(hs, (ss - b * sh) / m, b, var) : SlopeError{};
        if (var > 0.0 && std::abs(b) < slope_threshold(options.min_slope_significance, se.n_eff) *
                                           se.standard_error) {
          ++out.insignificant_samples;
        } else if (var > 0.0) {
          const Eigen::Vector3d wanted = b * k.cross(n);
          w = realisable_rotation(wanted, k, first.c_deg, options.kinematics);
          const double left_out = (wanted - w).norm();
          if (left_out > 1e-9 * wanted.norm()) {
            ++out.cut_samples;
            out.max_left_out_rad = std::max(out.max_left_out_rad, left_out);
          }
          ++out.tilted_samples;
        }
      }
    }
    FitSample r;
    r.position_mm = first.tcp_mm;
    r.normal = n.norm() > 0.0 ? Eigen::Vector3d(n) : Eigen::Vector3d(k);
    r.vector_mm = w;
    r.along_normal_only = false;
    out.rotations.push_back(r);
    for (std::size_t i = begin; i < end; ++i) {
      const PlacedVector& p = placed[order[i]];
      out.translations_mm[order[i]] = p.vector_mm - w.cross(height[order[i]] * k);
    }
    begin = end;
  }
  return out;
}

}  // namespace truecut::offline
