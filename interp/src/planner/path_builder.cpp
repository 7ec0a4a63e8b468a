// Canonical calls -> moves in the planning space.
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "output_map.hpp"
#include "path.hpp"
#include "spline_piece.hpp"
#include "truecut/interp/error.hpp"
#include "truecut/interp/nurbs.hpp"
#include "truecut/interp/path_geometry.hpp"

namespace truecut::interp::plan {

double norm(const Vec5& v) {
  double s = 0;
  for (double x : v)
    s += x * x;
  return std::sqrt(s);
}

Vec5 sub(const Vec5& a, const Vec5& b) {
  Vec5 r;
  for (int i = 0; i < 5; ++i)
    r[i] = a[i] - b[i];
  return r;
}

namespace {

constexpr double kMinLength = 1e-9;

double xyz_norm(const Vec5& v) {
  return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

struct Builder {
  const CanonProgram& program;
  const PlannerOptions& opt;
  Path out;

  bool tcp = false;
  double tcp_tool_length_mm = 0;  // tool length the TCP position `cur` refers to
  Vec5 cur{};                     // planning-space position (joint space at start)
  double feed_upm = 0;
  double unsynced_feed_upm = 0;  // F while G33/G33.1 feed at K per revolution
  double spindle_rpm = 0;        // last S word (G96: surface speed, m/min or ft/min)
  bool spindle_on = false;       // M3/M4 until M5
  bool css = false;              // G96 constant surface speed
  double css_max_rpm = 0;        // its D
  bool synced = false;           // between G33/G33.1's sync on and off
  bool spline_feeds = false;     // flush_spline: feed_upm is already per minute
  PathMode mode = PathMode::kContinuous;
  double tolerance_mm = 0;

  struct SplinePoint {
    Vec5 p;
    int line;
    double feed;
  };
  SplineMode spline_mode = SplineMode::kNone;
  std::vector<SplinePoint> spline;  // spline[0] is the start point
  CallContext spline_ctx;

  Builder(const CanonProgram& p, const PlannerOptions& o) : program(p), opt(o) {
    const auto& s = o.start_joints;
    cur = {s[0], s[1], s[2], s[3] * o.rotary_weight_mm_per_deg, s[4] * o.rotary_weight_mm_per_deg};
  }

  [[noreturn]] void fail(const CallContext& ctx, const std::string& what) const {
    const std::string file = ctx.file < static_cast<int>(program.files.size())
                                 ? program.files[ctx.file]
                                 : std::string("program");
    throw GcodeError({file, ctx.line, 0}, what);
  }

  int operation_id(const std::string& name) {
    if (name.empty()) return 0;
    for (size_t i = 0; i < out.operations.size(); ++i)
      if (out.operations[i] == name) return static_cast<int>(i) + 1;
    out.operations.push_back(name);
    return static_cast<int>(out.operations.size());
  }

  rt::AcTrtParams kinematics(const CallContext& ctx) const {
    rt::AcTrtParams k = opt.kinematics;
    k.tool_length_mm += ctx.tool_offset_mm.z;
    return k;
  }

  double scale(const CallContext& ctx) const {
    return ctx.units == LengthUnits::kInch ? 25.4 : 1.0;
  }

  // Program position -> planning space. Joint space: the machine position;
  // TCP mode: the TCP in the workpiece frame (no tool length offset).
  Vec5 to_planning(const Axes6& p, const CallContext& ctx) const {
    const Axes6 m = machine_position_mm(p, ctx);
    const double w = opt.rotary_weight_mm_per_deg;
    Vec5 r{m.x, m.y, m.z, w * m.a, w * m.c};
    if (tcp)
      for (int i = 0; i < 3; ++i)
        r[i] -= ctx.tool_offset_mm[i];
    return r;
  }

  // In TCP mode a new tool length moves the TCP, not the joints: `cur` is
  // re-expressed for the tool now in use.
  void rebase(const CallContext& ctx) {
    if (!tcp) return;
    const rt::AcTrtParams kin = kinematics(ctx);
    if (kin.tool_length_mm == tcp_tool_length_mm) return;
    rt::AcTrtParams old = kin;
    old.tool_length_mm = tcp_tool_length_mm;
    const double w = opt.rotary_weight_mm_per_deg;
    const MappedPoint mp = map_point(true, old, w, cur, {});
    const rt::ToolPose pose = rt::forward_ac(kin, mp.joints);
    cur = {pose.tcp_mm.x(), pose.tcp_mm.y(), pose.tcp_mm.z(), cur[3], cur[4]};
    tcp_tool_length_mm = kin.tool_length_mm;
  }

  // The spindle speed now (rpm): S, or under G96 the speed that keeps the
  // surface speed S at the tool's X distance from the work origin (at
  // the start of the move), at most D.
  double spindle_rpm_now(const CallContext& ctx) const {
    if (!spindle_on) return 0;
    if (!css) return spindle_rpm;
    const double surface_mm_per_min =
        spindle_rpm * (ctx.units == LengthUnits::kInch ? 304.8 : 1000);
    double x0 = ctx.g5x_mm.x + ctx.g92_mm.x;
    if (!tcp) x0 += ctx.tool_offset_mm.x;
    const double radius_mm = std::abs(cur[0] - x0);
    const double rpm = radius_mm > kMinLength
                           ? surface_mm_per_min / (2 * std::numbers::pi * radius_mm)
                           : std::numeric_limits<double>::infinity();
    // rs274's 1e30 (G96 without D) is no limit: at X 0 the speed is infinite.
    return css_max_rpm < 1e30 ? std::min(rpm, css_max_rpm) : rpm;
  }

  // The feed in program units per minute: G95's F per revolution times the
  // spindle speed at the start of the move (G33's sync sets its own).
  double feed_upm_now(const CallContext& ctx) const {
    if (ctx.feed_mode != FeedMode::kUnitsPerRevolution || synced || spline_feeds) return feed_upm;
    return feed_upm * spindle_rpm_now(ctx);
  }

  Move base_move(const CallContext& ctx, bool rapid) {
    Move m;
    m.tcp = tcp;
    m.rapid = rapid;
    m.mode = mode;
    m.tolerance_mm = tolerance_mm;
    m.kinematics = kinematics(ctx);
    m.line = ctx.line;
    m.tool = ctx.tool;
    m.operation = operation_id(ctx.operation);
    m.programmed_feed_mm_per_s = rapid ? 0 : feed_upm_now(ctx) * scale(ctx) / 60.0;
    const double rpm = spindle_rpm_now(ctx);
    m.spindle_rpm = std::isfinite(rpm) ? rpm : 0.0;  // G96 without D at X 0: unknown
    return m;
  }

  void set_feed(Move& m, const CallContext& ctx, double xyz_length) {
    m.metric = xyz_length > kMinLength ? FeedMetric::kXyz : FeedMetric::kRotary;
    if (m.rapid) {
      m.feed = opt.rapid_feed_mm_per_s > 0 ? opt.rapid_feed_mm_per_s
                                           : std::numeric_limits<double>::infinity();
      if (m.metric == FeedMetric::kRotary) m.feed = std::numeric_limits<double>::infinity();
      return;
    }
    const double f = feed_upm_now(ctx) / 60.0;
    if (ctx.feed_mode == FeedMode::kUnitsPerRevolution && !synced && !spline_feeds) {
      if (!spindle_on)
        fail(ctx, "feed per revolution (G95) with the spindle stopped: the move would not advance");
      if (!std::isfinite(f))
        fail(ctx,
             "feed per revolution (G95) under constant surface speed (G96) without D at X 0 (the "
             "work origin): the spindle speed and the feed are unbounded; program G96 with D");
    }
    if (!(f > 0)) fail(ctx, "feed move with zero feed rate");
    m.feed = m.metric == FeedMetric::kXyz ? f * scale(ctx) : f;
  }

  void add_line(const Vec5& target, const CallContext& ctx, bool rapid) {
    rebase(ctx);
    const Vec5 delta = sub(target, cur);
    const double len = norm(delta);
    if (len < kMinLength) return;
    Move m = base_move(ctx, rapid);
    m.piece.kind = PathPiece::kLine;
    m.piece.a = cur;
    for (int i = 0; i < 5; ++i)
      m.piece.b[i] = delta[i] / len;
    m.piece.length = len;
    set_feed(m, ctx, xyz_norm(delta));
    out.moves.push_back(m);
    cur = target;
  }

  // Planning space turned about Z by `degrees` (X Y only).
  static Vec5 turned(Vec5 v, double degrees) {
    if (degrees != 0) rotate_xy_deg(v[0], v[1], degrees);
    return v;
  }

  // Under an XY rotation (G10 L2 R) the arc is built in planning space
  // turned back by the rotation, where its plane is a coordinate plane
  // again (a G18/G19 arc stands in a turned vertical plane), and turned
  // forward after: centre, e1, e2 and drift.
  void add_arc(const ArcFeed& arc, const CallContext& ctx) {
    rebase(ctx);
    const path_geometry::PlaneAxes axes = path_geometry::plane_axes(arc.plane);
    const int first = axes.first, second = axes.second;
    const double turn = ctx.xy_rotation_deg;
    const Vec5 start = turned(cur, -turn);
    const Vec5 end = turned(to_planning(arc.end, ctx), -turn);
    // The centre in the plane, through the same offsets as the end point.
    Axes6 cprog = arc.end;
    cprog[first] = arc.center[first];
    cprog[second] = arc.center[second];
    const Vec5 cplan = turned(to_planning(cprog, ctx), -turn);
    const path_geometry::PlaneArc geo =
        path_geometry::plane_arc(start[first], start[second], end[first], end[second], cplan[first],
                                 cplan[second], arc.rotation);
    const double r0 = geo.start_radius_mm, r1 = geo.end_radius_mm;
    if (r0 < kMinLength) fail(ctx, "arc with zero radius");
    const double sweep = geo.sweep_rad;
    const double sx = start[first] - cplan[first], sy = start[second] - cplan[second];
    Move m = base_move(ctx, false);
    PathPiece& p = m.piece;
    p.kind = PathPiece::kArc;
    p.radius = r0;
    p.radius_end = r1;
    p.sweep_rad = sweep;
    p.a = start;  // off-plane coordinates start where the arc starts
    p.a[first] = cplan[first];
    p.a[second] = cplan[second];
    p.b = {};
    p.b[first] = sx / r0;
    p.b[second] = sy / r0;
    p.c = {};
    p.c[first] = -p.b[second];
    p.c[second] = p.b[first];
    double off2 = 0, off_xyz2 = 0;
    for (int i = 0; i < 5; ++i) {
      if (i == first || i == second) continue;
      const double d = end[i] - start[i];
      p.d[i] = d / sweep;
      off2 += d * d;
      if (i < 3) off_xyz2 += d * d;
    }
    const double arc_len = path_geometry::plane_length_mm(geo);
    p.length = std::sqrt(arc_len * arc_len + off2);
    set_feed(m, ctx, std::sqrt(arc_len * arc_len + off_xyz2));
    if (turn != 0) {
      p.a = turned(p.a, turn);
      p.b = turned(p.b, turn);
      p.c = turned(p.c, turn);
      p.d = turned(p.d, turn);
    }
    out.moves.push_back(m);
    cur = evaluate(p, p.length);
  }

  void add_dwell(double seconds, const CallContext& ctx) {
    if (seconds <= 0) return;
    Move m = base_move(ctx, false);
    m.dwell = true;
    m.dwell_s = seconds;
    m.piece.kind = PathPiece::kLine;
    m.piece.a = cur;
    m.piece.length = 0;
    out.moves.push_back(m);
  }

  void stop_here() {
    if (!out.moves.empty()) out.moves.back().stop_after = true;
  }

  void flush_spline() {
    if (spline.size() < 2) {
      spline.clear();
      return;
    }
    std::vector<Vec5> pts;
    for (const auto& s : spline)
      pts.push_back(s.p);
    double feed = std::numeric_limits<double>::infinity();
    for (size_t i = 1; i < spline.size(); ++i)
      feed = std::min(feed, spline[i].feed);
    SplineReport report;
    SplineFit fit = opt.spline_node_insertion
                        ? fit_spline_within(spline_mode, pts, opt.spline_tolerance_mm, &report)
                        : fit_spline(spline_mode, pts);
    if (!opt.spline_node_insertion) {
      report.mode = spline_mode;
      report.points = static_cast<int>(pts.size());
      report.tolerance_mm = opt.spline_tolerance_mm;
      report.error_before_mm = report.error_after_mm = fit.error_mm;
    }
    report.line = spline[1].line;
    out.splines.push_back(report);
    const double saved = feed_upm;
    feed_upm = feed;
    spline_feeds = true;
    for (const CubicSpan& span : fit.spans) {
      PathPiece piece;
      if (!cubic_piece(span, piece)) continue;
      Move m = base_move(spline_ctx, false);
      m.spline = true;
      m.piece = piece;
      const Vec5 d = sub(evaluate(piece, piece.length), piece.a);
      set_feed(m, spline_ctx, xyz_norm(d) + xyz_norm(piece.b));
      out.moves.push_back(m);
    }
    feed_upm = saved;
    spline_feeds = false;
    cur = spline.back().p;
    spline.clear();
  }

  void feed_point(const StraightFeed& f, const CallContext& ctx) {
    const Vec5 target = to_planning(f.end, ctx);
    if (ctx.spline == SplineMode::kNone) {
      flush_spline();
      add_line(target, ctx, false);
      return;
    }
    if (!spline.empty() && (ctx.spline != spline_mode)) flush_spline();
    if (spline.empty()) {
      rebase(ctx);
      spline_mode = ctx.spline;
      spline_ctx = ctx;
      spline.push_back({cur, ctx.line, feed_upm_now(ctx)});
    }
    if (norm(sub(target, spline.back().p)) < kMinLength) return;
    spline.push_back({target, ctx.line, feed_upm_now(ctx)});
  }

  // G5/G5.1/G5.2: the curve as straight feeds within spline_tolerance_mm
  // (nurbs_polyline), each chord a move of its own. In G93 the whole curve
  // takes 1/F minutes (F of its line): its length times F.
  void add_nurbs(const NurbsFeed& n, const CallContext& ctx) {
    const std::vector<NurbsPoint2> chords = nurbs_polyline(n, opt.spline_tolerance_mm / scale(ctx));
    const double saved = feed_upm;
    if (ctx.feed_mode == FeedMode::kInverseTime) {
      if (!(ctx.inverse_time_f > 0))
        fail(ctx,
             "NURBS (G5.2 ... G5.3) in inverse-time feed (G93) without F on its G5.3 line: the "
             "planner has no feed for it");
      double length = 0, x = n.points.front().x, y = n.points.front().y;
      for (const auto& c : chords) {
        length += std::hypot(c[0] - x, c[1] - y);
        x = c[0];
        y = c[1];
      }
      feed_upm = length * ctx.inverse_time_f;
    }
    for (const auto& c : chords) {
      Axes6 p = n.end;
      p.x = c[0];
      p.y = c[1];
      add_line(to_planning(p, ctx), ctx, false);
    }
    feed_upm = saved;
  }

  void set_tcp(bool on, const CallContext& ctx) {
    flush_spline();
    if (on == tcp) return;
    rebase(ctx);
    stop_here();
    const double w = opt.rotary_weight_mm_per_deg;
    const rt::AcTrtParams kin = kinematics(ctx);
    if (on) {
      const rt::ToolPose pose =
          rt::forward_ac(kin, rt::AcJoints{cur[0], cur[1], cur[2], cur[3] / w, cur[4] / w});
      cur = {pose.tcp_mm.x(), pose.tcp_mm.y(), pose.tcp_mm.z(), cur[3], cur[4]};
    } else {
      const MappedPoint mp = map_point(true, kin, w, cur, {});
      cur = {mp.joints.x_mm, mp.joints.y_mm, mp.joints.z_mm, cur[3], cur[4]};
    }
    tcp = on;
    tcp_tool_length_mm = kin.tool_length_mm;
  }

  void call(const CanonCall& c) {
    const CallContext& ctx = c.context;
    if (std::holds_alternative<StraightFeed>(c.op)) {
      feed_point(std::get<StraightFeed>(c.op), ctx);
      ++out.programmed_moves;
      return;
    }
    if (std::holds_alternative<SetFeedRate>(c.op)) {
      feed_upm = std::get<SetFeedRate>(c.op).units_per_minute;
      if (!spline.empty()) spline.back().feed = std::min(spline.back().feed, feed_upm_now(ctx));
      return;
    }
    if (const auto* sm = std::get_if<SetSpindleMode>(&c.op)) {
      css = sm->constant_surface_speed;
      css_max_rpm = sm->css_max_rpm;
      return;
    }
    // The spindle changes with the motion (no stop), as on a machine whose
    // spindle follows S and M3/M4/M5 on the fly.
    if (const auto* s = std::get_if<SetSpindleSpeed>(&c.op)) {
      spindle_rpm = s->rpm;
      return;
    }
    if (std::holds_alternative<StartSpindle>(c.op) || std::holds_alternative<StopSpindle>(c.op)) {
      spindle_on = std::holds_alternative<StartSpindle>(c.op);
      return;
    }
    if (std::holds_alternative<Comment>(c.op) || std::holds_alternative<Message>(c.op) ||
        std::holds_alternative<LogFile>(c.op) || std::holds_alternative<SetFeedMode>(c.op) ||
        std::holds_alternative<OutputBit>(c.op) || std::holds_alternative<OutputValue>(c.op))
      return;  // do not interrupt a spline
    flush_spline();
    if (const auto* t = std::get_if<StraightTraverse>(&c.op)) {
      add_line(to_planning(t->end, ctx), ctx, true);
      ++out.programmed_moves;
    } else if (const auto* a = std::get_if<ArcFeed>(&c.op)) {
      add_arc(*a, ctx);
      ++out.programmed_moves;
    } else if (const auto* nurbs = std::get_if<NurbsFeed>(&c.op)) {
      add_nurbs(*nurbs, ctx);
      ++out.programmed_moves;
    } else if (const auto* d = std::get_if<Dwell>(&c.op)) {
      add_dwell(d->seconds, ctx);
    } else if (const auto* sync = std::get_if<SpeedFeedSync>(&c.op)) {
      // G33/G33.1: K per revolution at the last S (a spindle at constant
      // speed), the programmed F again afterwards.
      if (sync->on) {
        unsynced_feed_upm = feed_upm;
        feed_upm = sync->units_per_rev * spindle_rpm;
      } else {
        feed_upm = unsynced_feed_upm;
      }
      synced = sync->on;
    } else if (const auto* tap = std::get_if<RigidTap>(&c.op)) {
      // In to the end, reverse, out to where the tap started.
      rebase(ctx);
      const Vec5 start = cur;
      add_line(to_planning(tap->end, ctx), ctx, false);
      stop_here();
      add_line(start, ctx, false);
      stop_here();
    } else if (const auto* probe = std::get_if<StraightProbe>(&c.op)) {
      // To where the probe tripped, then to where the machine stopped.
      add_line(to_planning(probe->trip, ctx), ctx, false);
      stop_here();
      add_line(to_planning(probe->stopped, ctx), ctx, false);
      stop_here();
    } else if (const auto* mc = std::get_if<SetMotionControlMode>(&c.op)) {
      mode = mc->mode;
      tolerance_mm = mc->tolerance * scale(ctx);
    } else if (const auto* tc = std::get_if<SetTcp>(&c.op)) {
      set_tcp(tc->on, ctx);
    } else if (std::holds_alternative<ChangeTool>(c.op) ||
               std::holds_alternative<ChangeToolNumber>(c.op) ||
               std::holds_alternative<ProgramStop>(c.op) ||
               std::holds_alternative<ProgramEnd>(c.op) || std::holds_alternative<Finish>(c.op) ||
               std::holds_alternative<UseToolLengthOffset>(c.op) ||
               std::holds_alternative<SetG5xOffset>(c.op) ||
               std::holds_alternative<SetG92Offset>(c.op)) {
      // The machine stops: the tool, the program or the coordinates change.
      stop_here();
      if (std::holds_alternative<ProgramEnd>(c.op)) set_tcp(false, ctx);
    }
  }
};

}  // namespace

Path build_path(const CanonProgram& program, const PlannerOptions& options) {
  Builder b(program, options);
  for (const CanonCall& c : program.calls)
    b.call(c);
  b.flush_spline();
  b.stop_here();
  return std::move(b.out);
}

}  // namespace truecut::interp::plan
