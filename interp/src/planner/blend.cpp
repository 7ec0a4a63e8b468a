// G64 corner blending: the corner C between two lines is replaced by the
// cubic B-spline with control points (C - t d1, C, C + t d2) and natural
// ends, i.e. two cubic spans that leave and rejoin the lines with matching
// tangent and zero curvature. Curvature is continuous along the blended
// path, so the joints' acceleration never steps and the jerk stays bounded
// through the corner (a tangent circular arc would step the acceleration by
// v^2/R where it meets the line).
//
// Its distance from the programmed lines is largest in the middle:
// t sin(θ)/6 for a turn θ (at most t sin(θ/2)/3 from the corner point), so
// t = 6 P / sin θ meets the G64 P tolerance. Each line gives at most half its
// length to the blend at either end, so neighbouring blends never overlap.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "path.hpp"
#include "spline_piece.hpp"
#include "truecut/interp/spline.hpp"

namespace truecut::interp::plan {

namespace {

bool blendable(const Move& a, const Move& b) {
  return a.piece.kind == PathPiece::kLine && b.piece.kind == PathPiece::kLine && !a.dwell &&
         !b.dwell && !a.spline && !b.spline && !a.stop_after && a.mode == PathMode::kContinuous &&
         a.tcp == b.tcp && a.piece.length > 0 && b.piece.length > 0;
}

}  // namespace

int insert_blends(std::vector<Move>& moves, const PlannerOptions& opt) {
  std::vector<double> original(moves.size());
  for (size_t i = 0; i < moves.size(); ++i)
    original[i] = moves[i].piece.length;
  std::vector<Move> out;
  out.reserve(moves.size() * 2);
  int blends = 0;
  for (size_t i = 0; i < moves.size(); ++i) {
    out.push_back(moves[i]);
    if (i + 1 >= moves.size() || !blendable(moves[i], moves[i + 1])) continue;
    Move& in = out.back();
    Move& next = moves[i + 1];
    const Vec5& d1 = in.piece.b;
    const Vec5& d2 = next.piece.b;
    double dot = 0;
    for (int k = 0; k < 5; ++k)
      dot += d1[k] * d2[k];
    const double theta = std::acos(std::clamp(dot, -1.0, 1.0));
    if (theta < 1e-9 || theta > std::numbers::pi - 1e-3) continue;
    const double limit =
        theta <= std::numbers::pi / 2 ? std::sin(theta) / 6.0 : std::sin(0.5 * theta) / 3.0;
    double t = in.tolerance_mm > 0 ? in.tolerance_mm / limit : opt.max_blend_length_mm;
    t = std::min(t, 0.5 * std::min(original[i], original[i + 1]));
    if (t < 1e-9) continue;
    const Vec5 corner = evaluate(in.piece, in.piece.length);
    Vec5 b1, b2;
    for (int k = 0; k < 5; ++k)
      b1[k] = corner[k] - t * d1[k], b2[k] = corner[k] + t * d2[k];
    const SplineFit fit = fit_spline(SplineMode::kBspline, {b1, corner, b2});
    in.piece.length -= t;
    for (int k = 0; k < 5; ++k)
      next.piece.a[k] += t * d2[k];
    next.piece.length -= t;
    Move blend = in;
    blend.stop_after = false;
    blend.rapid = in.rapid && next.rapid;
    // The blend obeys the feed of both moves it joins.
    blend.blend_metric_out = next.metric;
    blend.blend_feed_out = next.feed;
    for (const CubicSpan& span : fit.spans) {
      if (!cubic_piece(span, blend.piece)) continue;
      out.push_back(blend);
    }
    ++blends;
  }
  moves = std::move(out);
  return blends;
}

}  // namespace truecut::interp::plan
