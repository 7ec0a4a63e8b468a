// The oracle of the rewrite suites that correct by a constant vector: the
// interpreter runs the original program and the rewritten one, and every
// feed of the operation must come out shifted by the vector (its end met,
// the points in between on the shifted segment, arc or spline), every other
// move exactly where it went, in the same order and at the same feed, and
// the spindle and coolant must switch in the same order between the same
// moves.
// In G93 (inverse time) the pieces of a feed must take the original's time.
//
// Positions are compared in machine millimetres (machine_position_mm): the
// vector is a machine shift, whatever the program's units, offsets or XY
// rotation.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <string>
#include <variant>
#include <vector>

#include "truecut/interp/interpreter.hpp"
#include "truecut/interp/rewrite.hpp"
#include "truecut/interp/rs274_format.hpp"

namespace truecut::interp::testing {

struct PathMove {
  Eigen::Vector3d end_mm;
  bool feed_of_op = false;    // a feed of the operation (corrected), else kept exactly
  double feed = 0;            // F in force (program units)
  double inverse_time_f = 0;  // G93: the line's F (1 / minutes); else 0
  // An arc: its centre and axis (machine mm, unit); a spline: the box of its
  // control points, which holds the curve (positive weights).
  bool arc = false;
  Eigen::Vector3d center_mm = Eigen::Vector3d::Zero(), axis = Eigen::Vector3d::UnitZ();
  bool spline = false;
  Eigen::Vector3d box_lo_mm = Eigen::Vector3d::Zero(), box_hi_mm = Eigen::Vector3d::Zero();
  bool inch = false;
  // A canned cycle's move: the normal of its plane (machine axes). The
  // rewrite shifts a hole over the plane by the correction at its bottom
  // and the bottom along the normal (docs/rewrite.md), so a cycle's move
  // may end where it was, shifted over the plane, or shifted fully.
  bool cycle = false;
  Eigen::Vector3d cycle_normal = Eigen::Vector3d::UnitZ();
  bool traverse = false;
};

inline Eigen::Vector3d machine_xyz_mm(const Axes6& p, const CallContext& ctx) {
  const Axes6 m = machine_position_mm(p, ctx);
  return {m.x, m.y, m.z};
}

// The normal of an arc's plane in machine axes: the XY rotation turns X
// and Y about Z.
inline Eigen::Vector3d arc_axis(Plane plane, const CallContext& ctx) {
  if (plane == Plane::kXY) return Eigen::Vector3d::UnitZ();
  Axes6 n{};
  (plane == Plane::kXZ ? n.y : n.x) = 1;
  rotate_xy_deg(n.x, n.y, ctx.xy_rotation_deg);
  return {n.x, n.y, 0};
}

inline std::vector<PathMove> path_moves(const CanonProgram& p, const RewriteOptions& o) {
  std::vector<PathMove> out;
  double feed = 0;
  for (const CanonCall& c : p.calls) {
    const CallContext& ctx = c.context;
    if (const auto* f = std::get_if<SetFeedRate>(&c.op)) feed = f->units_per_minute;
    PathMove m;
    m.feed = feed;
    m.inch = ctx.units == LengthUnits::kInch;
    m.feed_of_op = ctx.operation == o.operation;
    if (ctx.feed_mode == FeedMode::kInverseTime) m.inverse_time_f = ctx.inverse_time_f;
    if (ctx.canned_cycle != 0) {
      m.cycle = true;
      m.cycle_normal = arc_axis(ctx.cycle_plane, ctx);
    }
    if (const auto* t = std::get_if<StraightTraverse>(&c.op)) {
      m.end_mm = machine_xyz_mm(t->end, ctx);
      m.feed_of_op = false;
      m.traverse = true;
      m.inverse_time_f = 0;
    } else if (const auto* f = std::get_if<StraightFeed>(&c.op)) {
      m.end_mm = machine_xyz_mm(f->end, ctx);
    } else if (const auto* a = std::get_if<ArcFeed>(&c.op)) {
      m.end_mm = machine_xyz_mm(a->end, ctx);
      Axes6 center = a->end;  // the axis coordinate is the end's
      if (a->plane == Plane::kXY) center.x = a->center.x, center.y = a->center.y;
      if (a->plane == Plane::kXZ) center.x = a->center.x, center.z = a->center.z;
      if (a->plane == Plane::kYZ) center.y = a->center.y, center.z = a->center.z;
      m.arc = true;
      m.center_mm = machine_xyz_mm(center, ctx);
      m.axis = arc_axis(a->plane, ctx);
    } else if (const auto* n = std::get_if<NurbsFeed>(&c.op)) {
      m.end_mm = machine_xyz_mm(n->end, ctx);
      m.spline = true;
      m.box_lo_mm = m.box_hi_mm = m.end_mm;
      for (const NurbsControlPoint& q : n->points) {
        Axes6 at = n->end;
        at.x = q.x, at.y = q.y;
        const Eigen::Vector3d v = machine_xyz_mm(at, ctx);
        m.box_lo_mm = m.box_lo_mm.cwiseMin(v);
        m.box_hi_mm = m.box_hi_mm.cwiseMax(v);
      }
    } else {
      continue;
    }
    out.push_back(m);
  }
  return out;
}

// A call that switches something on the machine (spindle, coolant, an
// output, an override, a stop, orient, a log line), and how many moves
// (path_moves) came before it.
struct MachineSwitch {
  std::string call;
  size_t moves_before;
};

inline std::vector<MachineSwitch> machine_switches(const CanonProgram& p) {
  std::vector<MachineSwitch> out;
  size_t moves = 0;
  for (const CanonCall& c : p.calls) {
    if (std::holds_alternative<StraightTraverse>(c.op) ||
        std::holds_alternative<StraightFeed>(c.op) || std::holds_alternative<ArcFeed>(c.op) ||
        std::holds_alternative<NurbsFeed>(c.op)) {
      ++moves;
    } else if (std::holds_alternative<SetSpindleSpeed>(c.op) ||
               std::holds_alternative<SetSpindleMode>(c.op) ||
               std::holds_alternative<StartSpindle>(c.op) ||
               std::holds_alternative<StopSpindle>(c.op) || std::holds_alternative<Coolant>(c.op) ||
               std::holds_alternative<OutputBit>(c.op) ||
               std::holds_alternative<OutputValue>(c.op) ||
               std::holds_alternative<FeedOverride>(c.op) ||
               std::holds_alternative<SpeedOverride>(c.op) ||
               std::holds_alternative<AdaptiveFeed>(c.op) ||
               std::holds_alternative<FeedHold>(c.op) ||
               std::holds_alternative<ProgramStop>(c.op) ||
               std::holds_alternative<OrientSpindle>(c.op) ||
               std::holds_alternative<WaitOrientComplete>(c.op) ||
               std::holds_alternative<LogFile>(c.op)) {
      out.push_back({format_rs274(c.op), moves});
    }
  }
  return out;
}

// `tolerance_mm` for a program in mm; 25.4 times it in inches (the written
// digits are inches).
inline void expect_same_path_shifted(const std::string& original, const std::string& rewritten,
                                     const RewriteOptions& o, const Eigen::Vector3d& offset_mm,
                                     const std::string& name = "p.ngc",
                                     double tolerance_mm = 2e-6) {
  using V = Eigen::Vector3d;
  // Each program run once; its moves and switches taken from that run.
  const CanonProgram original_run = Interpreter(o.interpreter).run_text(original, name);
  const CanonProgram rewritten_run = Interpreter(o.interpreter).run_text(rewritten, name);
  const std::vector<PathMove> want = path_moves(original_run, o);
  const std::vector<PathMove> got = path_moves(rewritten_run, o);
  size_t g = 0;
  std::vector<size_t> matched(want.size());  // the new program's move for each
  V prev_want = V::Zero();
  for (size_t i = 0; i < want.size(); ++i) {
    const double tol = want[i].inch ? 25.4 * tolerance_mm : tolerance_mm;
    const V target = want[i].end_mm + (want[i].feed_of_op ? offset_mm : V::Zero());
    // A canned cycle's move: where it was, shifted over the plane, or fully.
    const V& n = want[i].cycle_normal;
    const std::vector<V> cycle_targets = {want[i].end_mm,
                                          want[i].end_mm + offset_mm - offset_mm.dot(n) * n,
                                          want[i].end_mm + offset_mm};
    const auto at_target = [&](const V& p) {
      if (!want[i].cycle) return (p - target).norm() <= tol;
      return std::any_of(cycle_targets.begin(), cycle_targets.end(),
                         [&](const V& t) { return (p - t).norm() <= tol; });
    };
    const V from = prev_want;
    bool found = false;
    double minutes = 0;  // G93: the time of the pieces so far
    for (; g < got.size(); ++g) {
      const V p = got[g].end_mm;
      if (got[g].inverse_time_f > 0) minutes += 1 / got[g].inverse_time_f;
      if (at_target(p) && got[g].feed_of_op == want[i].feed_of_op &&
          got[g].traverse == want[i].traverse) {
        if (want[i].inverse_time_f > 0) {
          EXPECT_NEAR(minutes, 1 / want[i].inverse_time_f, 1e-9 / want[i].inverse_time_f)
              << "the pieces of G93 move " << i << " of the original take another time";
        } else if (!want[i].traverse) {
          EXPECT_EQ(got[g].feed, want[i].feed) << "move " << i << " of the original";
        }
        found = true;
        matched[i] = g;
        ++g;
        break;
      }
      // A move back from a corrected point to the original one (the last
      // original end), before a line the rewrite keeps as it is.
      if (i > 0 && !want[i].feed_of_op && !got[g].feed_of_op && (p - prev_want).norm() <= tol) {
        minutes = 0;
        continue;
      }
      // A point in between: on the segment, arc or spline from the last end
      // to this one.
      ASSERT_TRUE(want[i].feed_of_op && got[g].feed_of_op)
          << "at move " << i << " of the original, " << g << " of the new program: "
          << "the new program makes an extra move to " << p.transpose() << " before move " << i
          << " of the original (" << target.transpose() << ")\n"
          << rewritten;
      const V a = from, b = target - offset_mm, q = p - offset_mm;
      if (want[i].arc) {
        // Between the cylinders through the arc's start and end: LinuxCNC
        // takes an arc whose end is a little off the start's circle and
        // turns the radius over from one to the other.
        const V& c = want[i].center_mm;
        const V& n = want[i].axis;
        const auto radius = [&](const V& x) { return ((x - c) - (x - c).dot(n) * n).norm(); };
        const double r0 = std::min(radius(a), radius(b)), r1 = std::max(radius(a), radius(b));
        EXPECT_TRUE(radius(q) >= r0 - tol && radius(q) <= r1 + tol)
            << "point " << p.transpose() << " off the arc (move " << i << "): radius " << radius(q)
            << ", the arc's from " << radius(a) << " to " << radius(b);
        continue;
      }
      if (want[i].spline) {  // inside the box of the control points
        EXPECT_TRUE((q.array() >= want[i].box_lo_mm.array() - tol).all() &&
                    (q.array() <= want[i].box_hi_mm.array() + tol).all())
            << "point " << p.transpose() << " outside the spline's control points (move " << i
            << ")";
        continue;
      }
      const V d = b - a;
      const double t =
          d.squaredNorm() > 0 ? std::clamp((q - a).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
      EXPECT_LE((a + t * d - q).norm(), tol)
          << "point " << p.transpose() << " off the path from " << a.transpose() << " to "
          << b.transpose() << " (move " << i << ")";
    }
    ASSERT_TRUE(found) << "move " << i << " of the original (to " << target.transpose()
                       << ") is not in the new program\n"
                       << rewritten;
    prev_want = want[i].end_mm;
  }
  EXPECT_EQ(g, got.size()) << "the new program makes more moves than the original\n" << rewritten;

  // Each switch after the new program's match of the original move before
  // it and no later than that of the move after it.
  const std::vector<MachineSwitch> want_switches = machine_switches(original_run);
  const std::vector<MachineSwitch> got_switches = machine_switches(rewritten_run);
  ASSERT_EQ(got_switches.size(), want_switches.size()) << rewritten;
  for (size_t i = 0; i < want_switches.size(); ++i) {
    const MachineSwitch& w = want_switches[i];
    EXPECT_EQ(got_switches[i].call, w.call) << "machine switch " << i;
    const size_t k = w.moves_before;
    const size_t earliest = k > 0 ? matched[k - 1] + 1 : 0;
    const size_t latest = k < want.size() ? matched[k] : got.size();
    EXPECT_TRUE(got_switches[i].moves_before >= earliest && got_switches[i].moves_before <= latest)
        << "machine switch " << i << " (" << w.call << ") after " << got_switches[i].moves_before
        << " moves of the new program, which meets the "
        << "original's move " << k << " (the last before it) with its move " << earliest;
  }
}

}  // namespace truecut::interp::testing
