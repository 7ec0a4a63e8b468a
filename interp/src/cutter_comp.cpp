// Cutter radius compensation G40/G41/G42/G41.1/G42.1 as LinuxCNC 2.9's
// interpreter does it, in the XY (G17) and XZ (G18) planes.
//
// The tool path is offset by the tool radius to the left (G41) or right
// (G42) of the programmed path. Where a move ends depends on the next one,
// so each compensated move is held back (Emitter::hold) until the next
// move is known:
//  - entry: the first move goes from where the tool is to the programmed
//    end offset by the radius perpendicular to the move (a line) or to the
//    arc through that offset end (an arc);
//  - convex corner: an arc about the programmed corner joins the two offset
//    paths (a straight traverse for G0);
//  - concave corner: the held move is cut back to where the two offset paths
//    meet; if that reverses a held move, or an arc would sweep further than
//    programmed, the tool cannot reach the corner without gouging: an error;
//  - exit (G40): the held moves go out as they are, the next move starts
//    from the tool's compensated position and must be straight.
// All geometry is in program units, in the plane's two coordinates in
// ARC_FEED order (XY: x, y; XZ: z, x).
#include <cmath>
#include <numbers>
#include <string>

#include "block_executor.hpp"
#include "truecut/interp/path_geometry.hpp"
#include "truecut/rt/number_format.hpp"

namespace truecut::interp {

namespace {

constexpr double kPi = std::numbers::pi;
// Angles within this of a corner case count as that case (radians).
constexpr double kCornerTolerance_rad = 0.05;

struct Vec2 {
  double u = 0, v = 0;
};

Vec2 along(double angle_rad, double length) {
  return {length * std::cos(angle_rad), length * std::sin(angle_rad)};
}
double angle_of(Vec2 from, Vec2 to) {
  return std::atan2(to.v - from.v, to.u - from.u);
}
double distance(Vec2 a, Vec2 b) {
  return std::hypot(b.u - a.u, b.v - a.v);
}

// The signed angle an arc of `turn` turns (negative: clockwise) sweeps
// from `from` to `to` about `center`; 0 for turn 0.
double swept_rad(Vec2 from, Vec2 center, int turn, Vec2 to) {
  if (turn == 0) return 0;
  double a0 = angle_of(center, from), a1 = angle_of(center, to);
  if (turn > 0) {
    if (a1 <= a0) a1 += 2 * kPi;
    return a1 - a0 + (turn - 1) * 2 * kPi;
  }
  if (a0 <= a1) a0 += 2 * kPi;
  return a1 - a0 + (turn + 1) * 2 * kPi;
}

// The tool is inside an arc cut on `side` when the arc turns towards it.
bool tool_inside(int side, int turn) {
  return (side > 0 && turn > 0) || (side < 0 && turn < 0);
}

}  // namespace

void BlockExecutor::check_comp_plane_change(Plane next) const {
  if (s_.comp.side != 0 && next != s_.plane)
    fail(codes_.g_column[static_cast<int>(GGroup::kPlane)],
         "cannot change planes with cutter radius compensation on (G40 first)");
}

void BlockExecutor::comp_on(int code) {
  const int col = codes_.g_column[static_cast<int>(GGroup::kCutterComp)];
  const std::string name =
      code % 10 ? "G" + std::to_string(code / 10) + ".1" : "G" + std::to_string(code / 10);
  if (s_.plane != Plane::kXY && s_.plane != Plane::kXZ)
    fail(col, "cutter radius compensation only in the XY (G17) and XZ (G18) planes");
  if (s_.comp.side != 0)
    fail(col, "cannot turn cutter radius compensation on when it is on (" + name +
                  " after G41/G42 without G40)");
  int side = (code == 410 || code == 411) ? 1 : -1;
  double radius = 0;
  if (code == 411 || code == 421) {
    if (!b_->has('d')) fail(col, name + " with no D word (D is the tool diameter)");
    radius = b_->value('d') / 2;
    if (b_->has('l')) {
      if (s_.plane != Plane::kXZ)
        fail(column_of('l'), name + " with an L word, but the plane is not G18");
      const double l = b_->value('l');
      if (l != 0 && l != 9)
        fail(column_of('l'), name +
                                 " L (lathe tool orientation 1-8) is not supported: truecut is "
                                 "for mills (L0 or L9 only)");
    }
  } else {
    int tool = s_.tool;
    if (b_->has('d')) {
      const double d = b_->value('d');
      const double nearest = std::floor(d + 0.5);
      if (std::fabs(nearest - d) >= 0.0001 || nearest < 0)
        fail(column_of('d'), name + " needs D to be a whole number (a tool number)");
      if (nearest > kLargestWholeWord)
        fail(column_of('d'), "D" + rt::format_shortest(d) + ": no such tool in the tool table");
      if (nearest > 0) tool = static_cast<int>(nearest);
    }
    if (tool != 0) {
      const ToolEntry* e = tools_.find(tool);
      if (!e)
        fail(b_->has('d') ? column_of('d') : col,
             "tool " + std::to_string(tool) + " for " + name + " is not in the tool table");
      radius = s_.to_program(0, e->diameter_mm) / 2;
      if (e->orientation != 0 && e->orientation != 9) {
        if (s_.plane != Plane::kXZ)
          fail(col, name + " with a lathe tool (orientation Q" + std::to_string(e->orientation) +
                        " in the tool table), but the plane is not G18");
        fail(col, name + " with a lathe tool (orientation Q" + std::to_string(e->orientation) +
                      " in the tool table) is not supported: truecut is for mills");
      }
    }
  }
  if (radius < 0) {  // a negative diameter cuts on the other side
    radius = -radius;
    side = -side;
  }
  out_.emit(Comment{side > 0 ? "interpreter: cutter radius compensation on left"
                             : "interpreter: cutter radius compensation on right"});
  s_.comp.side = side;
  s_.comp.radius = radius;
  s_.comp.first_move = true;
}

void BlockExecutor::comp_off() {
  out_.emit(Comment{"interpreter: cutter radius compensation off"});
  CutterCompState& c = s_.comp;
  if (c.active() && !c.first_move) {
    const auto ax = path_geometry::plane_axes(s_.plane);
    const Axes6 here = s_.program_position();
    move_held_end(here[ax.first], here[ax.second],
                  codes_.g_column[static_cast<int>(GGroup::kCutterComp)]);
    comp_flush();
    // LinuxCNC takes the programmed point as the current one: the next
    // move (which must be straight) starts from where the tool is.
    const Axes6 programmed = s_.machine_position(c.programmed);
    for (int i = 0; i < 3; ++i)
      s_.position_mm[i] = programmed[i];
    c.arc_not_allowed = true;
  }
  c.side = 0;
  c.first_move = true;
}

void BlockExecutor::comp_flush() {
  out_.flush();
  s_.comp.endpoint_valid = false;
}

void BlockExecutor::check_comp_codes() const {
  if (s_.comp.side == 0) return;
  const int nm = codes_.g[static_cast<int>(GGroup::kNonModal)];
  const int nm_col = codes_.g_column[static_cast<int>(GGroup::kNonModal)];
  if (codes_.m[static_cast<int>(MGroup::kToolChange)] == 60)
    fail(codes_.m_column[static_cast<int>(MGroup::kToolChange)],
         "cannot change tools with cutter radius compensation on (G40 first)");
  // What LinuxCNC executes after G40 on the same line is allowed with it.
  if (codes_.g[static_cast<int>(GGroup::kCutterComp)] == 400) return;
  if (codes_.g[static_cast<int>(GGroup::kRetract)] >= 0)
    fail(codes_.g_column[static_cast<int>(GGroup::kRetract)],
         "cannot change the canned cycle retract mode (G98/G99) with cutter radius "
         "compensation on (G40 first)");
  if (codes_.g[static_cast<int>(GGroup::kToolLength)] >= 0)
    fail(codes_.g_column[static_cast<int>(GGroup::kToolLength)],
         "cannot change the tool length offset with cutter radius compensation on (G40 first)");
  if (codes_.g[static_cast<int>(GGroup::kCoordSystem)] >= 0)
    fail(codes_.g_column[static_cast<int>(GGroup::kCoordSystem)],
         "cannot change coordinate systems with cutter radius compensation on (G40 first)");
  if (codes_.g[static_cast<int>(GGroup::kPathControl)] >= 0)
    fail(codes_.g_column[static_cast<int>(GGroup::kPathControl)],
         "cannot change the path control mode (G61/G61.1/G64) with cutter radius compensation "
         "on (G40 first)");
  if (nm == 920 || nm == 520)
    fail(nm_col, "cannot change axis offsets (G52/G92) with cutter radius compensation on");
  if (nm == 280 || nm == 300)
    fail(nm_col, "cannot use G28 or G30 with cutter radius compensation on");
  if (nm == 100 && b_->has('l') && (b_->value('l') == 2 || b_->value('l') == 20) && b_->has('p') &&
      (b_->value('p') == 0 || b_->value('p') == s_.coord_index))
    fail(nm_col, "cannot change the active coordinate system with cutter radius compensation on");
}

void BlockExecutor::move_held_end(double u, double v, int column) {
  CutterCompState& c = s_.comp;
  auto& held = out_.held();
  if (held.empty()) return;
  const auto ax = path_geometry::plane_axes(s_.plane);
  const Vec2 to{u, v};
  const Vec2 start{c.endpoint[0], c.endpoint[1]};
  for (HeldCall& h : held) {
    if (auto* arc = std::get_if<ArcFeed>(&h.call.op)) {
      const Vec2 center{arc->center[ax.first], arc->center[ax.second]};
      const Vec2 end{arc->end[ax.first], arc->end[ax.second]};
      const double r1 = distance(center, end), r2 = distance(center, to);
      if (std::fabs(r1 - r2) > 0.01)
        fail(column, "internal error: cutter compensation made an arc with mismatched radii");
      const double sweep = swept_rad(start, center, arc->rotation, to);
      if (h.sweep_rad != 0 && c.endpoint_valid && std::fabs(sweep) > std::fabs(h.sweep_rad) + 0.001)
        fail(column,
             "arc move in a concave corner cannot be reached by the tool without gouging "
             "(cutter radius compensation)");
      arc->end[ax.first] = u;
      arc->end[ax.second] = v;
      continue;
    }
    Axes6* end = nullptr;
    const char* what = "";
    if (auto* f = std::get_if<StraightFeed>(&h.call.op)) end = &f->end, what = "straight feed";
    if (auto* t = std::get_if<StraightTraverse>(&h.call.op))
      end = &t->end, what = "straight traverse";
    if (!end) continue;
    const double dot = h.direction[0] * (u - start.u) + h.direction[1] * (v - start.v);
    if (c.endpoint_valid && dot < 0)
      fail(column, std::string(what) +
                       " in a concave corner cannot be reached by the tool without gouging (cutter "
                       "radius compensation)");
    (*end)[ax.first] = u;
    (*end)[ax.second] = v;
  }
  comp_flush();
  c.endpoint[0] = u;
  c.endpoint[1] = v;
  c.endpoint_valid = true;
}

namespace {
const ArcFeed* front_arc(std::vector<HeldCall>& held) {
  return held.empty() ? nullptr : std::get_if<ArcFeed>(&held.front().call.op);
}
}  // namespace

void BlockExecutor::comp_straight(bool rapid, const Axes6& target, int column) {
  CutterCompState& c = s_.comp;
  const auto ax = path_geometry::plane_axes(s_.plane);
  const Axes6 end = s_.program_position(target);  // programmed
  const Axes6 here = s_.program_position();       // where the tool is
  const Vec2 p{end[ax.first], end[ax.second]};
  const Vec2 cur{here[ax.first], here[ax.second]};
  const double r = c.radius;
  Axes6 tool_end = end;
  Vec2 tool{};
  double direction[2] = {0, 0};
  if (c.first_move) {
    if (distance(cur, p) <= r)
      fail(column, "the cutter compensation entry move is not longer than the tool radius");
    const double a = angle_of(cur, p) + c.side * kPi / 2;
    tool = {p.u + r * std::cos(a), p.v + r * std::sin(a)};
    c.endpoint[0] = cur.u;
    c.endpoint[1] = cur.v;
    c.endpoint_valid = true;
    direction[0] = std::cos(a);
    direction[1] = std::sin(a);
    c.first_move = false;
  } else {
    const Vec2 o{c.programmed[ax.first], c.programmed[ax.second]};
    if (p.u == o.u && p.v == o.v) {
      tool = cur;  // no motion in the plane
    } else {
      double theta = angle_of(o, cur), alpha = angle_of(o, p), beta, gamma;
      if (c.side > 0) {
        if (theta < alpha) theta += 2 * kPi;
        beta = theta - alpha - kPi / 2;
        gamma = kPi / 2;
      } else {
        if (alpha < theta) alpha += 2 * kPi;
        beta = alpha - theta - kPi / 2;
        gamma = -kPi / 2;
      }
      const Vec2 off = along(alpha + gamma, r);
      tool = {p.u + off.u, p.v + off.v};
      const Vec2 mid{o.u + off.u, o.v + off.v};
      const ArcFeed* prev = front_arc(out_.held());
      const bool concave =
          beta < -kCornerTolerance_rad || beta > kPi + kCornerTolerance_rad ||
          // arc then line over the top of an "h": stay on the outside
          (beta > kPi - kCornerTolerance_rad && prev &&
           ((c.side < 0 && prev->rotation > 0) || (c.side > 0 && prev->rotation < 0)));
      if (!concave && beta > kCornerTolerance_rad) {  // convex: round the corner
        move_held_end(cur.u, cur.v, column);
        Axes6 corner = end;
        corner[ax.first] = mid.u;
        corner[ax.second] = mid.v;
        corner[ax.normal] = here[ax.normal];
        if (!rapid) {
          ArcFeed a;
          a.end = corner;
          a.center[ax.first] = o.u;
          a.center[ax.second] = o.v;
          a.plane = s_.plane;
          a.rotation = c.side > 0 ? -1 : 1;
          out_.hold(std::move(a));
        } else {
          out_.hold(StraightTraverse{corner});
        }
        comp_flush();
        c.endpoint[0] = mid.u;
        c.endpoint[1] = mid.v;
        c.endpoint_valid = true;
      } else if (concave) {
        Vec2 meet;
        if (!prev) {  // line then line: back up along the held line
          const double half_corner = (beta + kPi) / 2;
          if (half_corner == 0)
            fail(column, "a zero degree inside corner is invalid for cutter compensation");
          const Vec2 back = along(theta + gamma, r / std::tan(half_corner));
          meet = {cur.u + back.u, cur.v + back.v};
        } else {  // arc then line: where the offset line meets the offset arc
          const Vec2 pc{prev->center[ax.first], prev->center[ax.second]};
          const double old_radius = distance(pc, {prev->end[ax.first], prev->end[ax.second]});
          const double th = angle_of(o, p) + (prev->rotation > 0 ? kPi / 2 : -kPi / 2);
          const double phi = angle_of(o, pc);
          const bool inside = tool_inside(c.side, prev->rotation);
          const double programmed_radius = inside ? old_radius + r : old_radius - r;
          const double d = programmed_radius * std::cos(th - phi);
          const double l = (inside ? d - r : d + r) / old_radius;
          if (l > 1.0 || l < -1.0)
            fail(column,
                 "arc to straight motion makes a corner the compensated tool can't fit in "
                 "without gouging");
          const double turn_sign = prev->rotation > 0 ? 1 : -1;
          const double ang = (inside ? -turn_sign : turn_sign) * std::acos(l) + th + kPi;
          meet = {pc.u + old_radius * std::cos(ang), pc.v + old_radius * std::sin(ang)};
        }
        move_held_end(meet.u, meet.v, column);
      } else {  // straight on (or tangent)
        comp_flush();
        c.endpoint[0] = cur.u;
        c.endpoint[1] = cur.v;
        c.endpoint_valid = true;
      }
      direction[0] = p.u - o.u;
      direction[1] = p.v - o.v;
    }
  }
  tool_end[ax.first] = tool.u;
  tool_end[ax.second] = tool.v;
  HeldCall& h = rapid ? out_.hold(StraightTraverse{tool_end}) : out_.hold(StraightFeed{tool_end});
  h.direction[0] = direction[0];
  h.direction[1] = direction[1];
  c.programmed = end;
  set_compensated_position(tool_end);
}

void BlockExecutor::set_compensated_position(const Axes6& program_point) {
  s_.position_mm = s_.machine_position(program_point);
  last_program_position_ = program_point;
}

void BlockExecutor::comp_arc(const ArcRequest& req, const ArcResult& res, const Axes6& end,
                             int column) {
  CutterCompState& c = s_.comp;
  const auto ax = path_geometry::plane_axes(s_.plane);
  const Axes6 here = s_.program_position();
  const Vec2 cur{here[ax.first], here[ax.second]};
  const Vec2 e{end[ax.first], end[ax.second]};
  const Vec2 k{res.center[0], res.center[1]};
  const double r = c.radius;
  const int turn = res.rotation;
  const bool inside = tool_inside(c.side, turn);
  auto hold_arc = [&](Vec2 to, Vec2 center, int rotation, double normal, double sweep) {
    ArcFeed a;
    a.end = end;
    a.end[ax.first] = to.u;
    a.end[ax.second] = to.v;
    a.end[ax.normal] = normal;
    a.center[ax.first] = center.u;
    a.center[ax.second] = center.v;
    a.plane = s_.plane;
    a.rotation = rotation;
    out_.hold(std::move(a)).sweep_rad = sweep;
  };
  const char* too_big = "tool radius not less than arc radius with cutter radius compensation";
  Vec2 tool;
  if (c.first_move) {
    // Entry arc: from where the tool is to the programmed end moved by the
    // radius, about the centre that keeps both at one distance.
    if (distance(cur, e) <= r)
      fail(column, "the cutter compensation entry arc is not longer than the tool radius");
    if (inside && distance(k, cur) <= r) fail(column, too_big);
    const double gamma = inside ? angle_of(e, k) : angle_of(k, e);
    tool = {e.u + r * std::cos(gamma), e.v + r * std::sin(gamma)};
    const double half_chord = distance(cur, tool) / 2;
    const double toward_center = angle_of(tool, k);
    const double corner = angle_of(tool, cur) - toward_center;
    if (std::fabs(std::cos(corner)) < 0.0001) fail(column, too_big);
    const double to_center = half_chord / std::cos(corner);
    const Vec2 center{tool.u + to_center * std::cos(toward_center),
                      tool.v + to_center * std::sin(toward_center)};
    hold_arc(tool, center, turn, end[ax.normal], swept_rad(cur, center, turn, tool));
    c.first_move = false;
  } else {
    const Vec2 o{req.start[0], req.start[1]};  // the programmed start
    const double arc_radius = distance(k, e);
    const double theta = angle_of(o, cur) - c.side * kPi / 2;  // direction at the corner
    double delta = angle_of(o, k);
    const double alpha = req.clockwise ? delta + kPi / 2 : delta - kPi / 2;
    double beta = c.side > 0 ? theta - alpha : alpha - theta;
    if (beta > 1.5 * kPi)
      beta -= 2 * kPi;
    else if (beta < -kPi / 2)
      beta += 2 * kPi;
    double gamma;
    if (inside) {
      gamma = angle_of(e, k);
      if (arc_radius <= r) fail(column, too_big);
    } else {
      gamma = angle_of(k, e);
      delta += kPi;
    }
    tool = {e.u + r * std::cos(gamma), e.v + r * std::sin(gamma)};
    const double sweep = swept_rad(o, k, turn, e);
    const bool concave = beta < -kCornerTolerance_rad || beta > kPi + kCornerTolerance_rad ||
                         // tangent arcs meeting over the top of an "m": convex
                         (std::fabs(beta - kPi) < kCornerTolerance_rad && !inside);
    if (concave) {
      const ArcFeed* prev = front_arc(out_.held());
      Vec2 meet;
      if (!prev) {  // line then arc
        const double across = arc_radius * std::sin(beta - kPi / 2);
        const double from_center = inside ? arc_radius - r : arc_radius + r;
        const double l = (inside ? across + r : across - r) / from_center;
        if (l > 1.0 || l < -1.0)
          fail(column,
               "arc move in a concave corner cannot be reached by the tool without gouging "
               "(cutter radius compensation)");
        double ang;
        if (inside)
          ang = turn > 0 ? theta + std::asin(l) : theta - std::asin(l);
        else
          ang = turn > 0 ? theta + kPi - std::asin(l) : theta + kPi + std::asin(l);
        meet = {k.u + from_center * std::cos(ang), k.v + from_center * std::sin(ang)};
      } else {  // arc then arc: where the two offset arcs cross
        const Vec2 pc{prev->center[ax.first], prev->center[ax.second]};
        const double old_radius = distance(pc, {prev->end[ax.first], prev->end[ax.second]});
        const double new_radius = inside ? arc_radius - r : arc_radius + r;
        const double centers = distance(pc, k);
        if (old_radius == 0 || centers == 0)
          fail(column, "arc to arc motion is invalid because the arcs have the same center");
        const double cos_pull =
            (old_radius * old_radius + centers * centers - new_radius * new_radius) /
            (2 * old_radius * centers);
        if (cos_pull > 1.0 || cos_pull < -1.0)
          fail(column,
               "arc to arc motion makes a corner the compensated tool can't fit in without "
               "gouging");
        const double pull = std::acos(cos_pull);
        const double dir_cc = angle_of(pc, k);
        const bool prev_inside = tool_inside(c.side, prev->rotation);
        const double sign = (prev_inside == (turn > 0)) ? 1 : -1;
        const double ang = dir_cc + sign * pull;
        meet = {pc.u + old_radius * std::cos(ang), pc.v + old_radius * std::sin(ang)};
      }
      move_held_end(meet.u, meet.v, column);
      hold_arc(tool, k, turn, end[ax.normal], sweep);
    } else if (beta > kCornerTolerance_rad) {  // convex: an arc about the corner first
      const Vec2 mid{o.u + r * std::cos(delta), o.v + r * std::sin(delta)};
      comp_flush();
      hold_arc(mid, o, c.side > 0 ? -1 : 1, here[ax.normal], 0);
      comp_flush();
      c.endpoint[0] = mid.u;
      c.endpoint[1] = mid.v;
      c.endpoint_valid = true;
      hold_arc(tool, k, turn, end[ax.normal], sweep);
    } else {  // tangent
      comp_flush();
      c.endpoint[0] = cur.u;
      c.endpoint[1] = cur.v;
      // rs274 2.9 checks no sweep after a tangent join (measured: random
      // profiles against rs274 disagree otherwise).
      c.endpoint_valid = false;
      hold_arc(tool, k, turn, end[ax.normal], sweep);
    }
  }
  c.programmed = end;
  Axes6 tool_end = end;
  tool_end[ax.first] = tool.u;
  tool_end[ax.second] = tool.v;
  set_compensated_position(tool_end);
}

}  // namespace truecut::interp
