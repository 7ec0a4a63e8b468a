#include "truecut/offline/tool_path.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <numbers>
#include <stdexcept>
#include <variant>

#include "truecut/interp/nurbs.hpp"
#include "truecut/interp/path_geometry.hpp"
#include "truecut/interp/spline.hpp"

namespace truecut::offline {

namespace {

using interp::Axes6;
constexpr double kDeg = std::numbers::pi / 180.0;

Eigen::Vector3d axis_from_ac(double a_deg, double c_deg) {
  const double a = a_deg * kDeg, c = c_deg * kDeg;
  return {std::sin(a) * std::sin(c), std::sin(a) * std::cos(c), std::cos(a)};
}

bool rotary_at_zero(const Axes6& p) {
  const double c = std::remainder(p.c, 360.0);
  return std::abs(p.a) < 1e-9 && std::abs(c) < 1e-9;
}

class Sampler {
 public:
  Sampler(const ToolPathOptions& options, ToolPath& out) : opt_(options), out_(out) {
    if (!(options.step_mm > 0.0) || !(options.max_axis_step_deg > 0.0) ||
        !(options.spline_tolerance_mm > 0.0))
      throw std::invalid_argument("tool path sampling steps must be positive");
  }

  void call(const interp::CanonCall& c) {
    const bool spline_feed = c.context.spline != interp::SplineMode::kNone &&
                             std::holds_alternative<interp::StraightFeed>(c.op);
    if (!spline_feed && !is_passive(c.op)) flush_spline();
    const double k = c.context.units == interp::LengthUnits::kInch ? 25.4 : 1.0;
    if (const auto* t = std::get_if<interp::StraightTraverse>(&c.op)) {
      cur_ = to_mm(t->end, k);
      ++out_.rapid_moves;
      need_start_ = true;
    } else if (const auto* f = std::get_if<interp::StraightFeed>(&c.op)) {
      const Axes6 end = to_mm(f->end, k);
      ++out_.feed_moves;
      if (spline_feed) {
        if (spline_.empty()) {
          spline_.push_back(vec5(cur_));
          spline_ctx_ = c.context;
          spline_mode_ = c.context.spline;
        }
        spline_.push_back(vec5(end));
      } else {
        const Axes6 start = cur_;
        emit_move(c.context, start, end,
                  [&](double s) { return interp::path_geometry::line_point_at(start, end, s, 6); });
      }
      cur_ = end;
    } else if (const auto* a = std::get_if<interp::ArcFeed>(&c.op)) {
      ++out_.feed_moves;
      emit_arc(*a, c.context, k);
    } else if (const auto* n = std::get_if<interp::NurbsFeed>(&c.op)) {
      // G5/G5.1/G5.2: chords within the spline tolerance, each sampled.
      ++out_.feed_moves;
      for (const auto& chord : interp::nurbs_polyline(*n, opt_.spline_tolerance_mm / k)) {
        const Axes6 start = cur_;
        Axes6 end = to_mm(n->end, k);
        end.x = chord[0] * k;
        end.y = chord[1] * k;
        emit_move(c.context, start, end,
                  [&](double s) { return interp::path_geometry::line_point_at(start, end, s, 6); });
        cur_ = end;
      }
    } else if (std::holds_alternative<interp::ChangeTool>(c.op) ||
               std::holds_alternative<interp::ChangeToolNumber>(c.op) ||
               std::holds_alternative<interp::SetTcp>(c.op)) {
      need_start_ = true;
    }
  }

  void finish() { flush_spline(); }

 private:
  static bool is_passive(const interp::CanonOp& op) {
    return std::holds_alternative<interp::Comment>(op) ||
           std::holds_alternative<interp::Message>(op) ||
           std::holds_alternative<interp::SetFeedRate>(op);
  }
  static Axes6 to_mm(Axes6 p, double k) {
    p.x *= k;
    p.y *= k;
    p.z *= k;
    return p;
  }
  static interp::Vec5 vec5(const Axes6& p) { return {p.x, p.y, p.z, p.a, p.c}; }

  std::int32_t operation_index(const std::string& name) {
    if (name.empty()) return -1;
    auto [it, added] = ops_.try_emplace(name, static_cast<std::int32_t>(out_.operations.size()));
    if (added) out_.operations.push_back(name);
    return it->second;
  }

  // Samples pos(s), s in [0, 1], from start to end with the step limits; the
  // tip distance is measured along pos on a fine pre-sampling.
  void emit_move(const interp::CallContext& ctx, const Axes6& start, const Axes6& end,
                 const std::function<Axes6(double)>& pos) {
    if (!ctx.tcp && (!rotary_at_zero(in_workpiece_frame(start, ctx)) ||
                     !rotary_at_zero(in_workpiece_frame(end, ctx)))) {
      if (out_.skipped_rotated_moves++ == 0) out_.first_skipped_line = ctx.line;
      need_start_ = true;
      return;
    }
    constexpr int kProbe = 16;
    double length = 0.0;
    Axes6 prev = start;
    for (int i = 1; i <= kProbe; ++i) {
      const Axes6 p = pos(double(i) / kProbe);
      length += std::hypot(p.x - prev.x, p.y - prev.y, p.z - prev.z);
      prev = p;
    }
    const double turn = std::max(std::abs(end.a - start.a), std::abs(end.c - start.c));
    const double n_real =
        std::max({1.0, std::ceil(length / opt_.step_mm), std::ceil(turn / opt_.max_axis_step_deg)});
    const int n = static_cast<int>(std::min(n_real, 1e7));
    const std::int32_t op = operation_index(ctx.operation);
    if (need_start_) {
      push(ctx, op, start);
      need_start_ = false;
    }
    for (int i = 1; i <= n; ++i)
      push(ctx, op, pos(double(i) / n));
  }

  // Program point (mm) → where the controller puts it in the workpiece
  // frame (the machine frame at A = C = 0, as the real-time component and
  // the rewriter see it): X Y Z as interp::machine_position_mm without the
  // tool length (this is the tip), A and C with their offsets.
  static Axes6 in_workpiece_frame(Axes6 p, const interp::CallContext& ctx) {
    double x = p.x + ctx.g92_mm.x, y = p.y + ctx.g92_mm.y;
    if (ctx.xy_rotation_deg != 0) interp::rotate_xy_deg(x, y, ctx.xy_rotation_deg);
    p.x = x + ctx.g5x_mm.x;
    p.y = y + ctx.g5x_mm.y;
    p.z += ctx.g92_mm.z + ctx.g5x_mm.z;
    for (int i = 3; i < 6; ++i)
      p[i] += ctx.g5x_mm[i] + ctx.g92_mm[i] + ctx.tool_offset_mm[i];
    return p;
  }

  void push(const interp::CallContext& ctx, std::int32_t op, const Axes6& program_point) {
    const Axes6 p = in_workpiece_frame(program_point, ctx);
    ToolPathSample s;
    s.tip_mm = {p.x, p.y, p.z};
    s.axis = ctx.tcp ? axis_from_ac(p.a, p.c) : Eigen::Vector3d::UnitZ();
    s.c_deg = ctx.tcp ? p.c : 0.0;
    s.tool = ctx.tool;
    s.line = ctx.line;
    s.operation = op;
    out_.samples.push_back(s);
  }

  void emit_arc(const interp::ArcFeed& arc, const interp::CallContext& ctx, double k) {
    const interp::path_geometry::PlaneAxes axes = interp::path_geometry::plane_axes(arc.plane);
    const Axes6 start = cur_;
    const Axes6 end = to_mm(arc.end, k);
    const interp::path_geometry::PlaneArc geo = interp::path_geometry::plane_arc(
        start[axes.first], start[axes.second], end[axes.first], end[axes.second],
        arc.center[axes.first] * k, arc.center[axes.second] * k, arc.rotation);
    cur_ = end;
    if (geo.start_radius_mm < 1e-9) return;  // the interpreter rejects these; nothing to cut
    emit_move(ctx, start, end, [&](double s) {
      // off-plane axes and rotaries: linear
      return interp::path_geometry::arc_point_at(axes, geo, start, end, s, 6);
    });
  }

  void flush_spline() {
    if (spline_.size() < 2) {
      spline_.clear();
      return;
    }
    const interp::SplineFit fit =
        interp::fit_spline_within(spline_mode_, spline_, opt_.spline_tolerance_mm);
    for (const interp::CubicSpan& span : fit.spans) {
      auto at = [&](double t) {
        Axes6 p;
        for (int i = 0; i < 5; ++i) {
          const double v = span.c0[i] + t * (span.c1[i] + t * (span.c2[i] + t * span.c3[i]));
          p[i == 4 ? 5 : i] = v;  // (x, y, z, a, c) -> Axes6 (B stays 0)
        }
        return p;
      };
      emit_move(spline_ctx_, at(0.0), at(1.0), at);
    }
    spline_.clear();
  }

  const ToolPathOptions& opt_;
  ToolPath& out_;
  Axes6 cur_{};
  bool need_start_ = true;
  std::map<std::string, std::int32_t> ops_;
  std::vector<interp::Vec5> spline_;
  interp::CallContext spline_ctx_;
  interp::SplineMode spline_mode_ = interp::SplineMode::kNone;
};

}  // namespace

ToolPath sample_tool_path(const interp::CanonProgram& program, const ToolPathOptions& options) {
  ToolPath out;
  Sampler sampler(options, out);
  for (const interp::CanonCall& c : program.calls)
    sampler.call(c);
  sampler.finish();
  return out;
}

}  // namespace truecut::offline
