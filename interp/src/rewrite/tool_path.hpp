// The tool path as truecut's planner moves it (planner/path_builder.cpp),
// so the densified points lie where the machine would be: in joint space
// (no TRAORI) a point is the machine position (X Y Z A C) and moves are
// straight in all five axes, arcs in their plane with the other axes
// linear in the angle; under TRAORI a point is (tip in the workpiece frame,
// A, C) with A and C interpolated along the tip's path.
#pragma once

#include <array>
#include <vector>

#include "neighbours.hpp"
#include "truecut/interp/canon.hpp"
#include "truecut/interp/path_geometry.hpp"
#include "truecut/rt/core/kinematics_ac.hpp"

namespace truecut::interp::rewrite {

using Vec5 = std::array<double, 5>;  // x y z (mm) a c (deg)

class ToolPath {
 public:
  explicit ToolPath(const rt::AcTrtParams& kinematics) : base_(kinematics) {}

  // Follows the non-motion calls that move the planning point (TRAORI on or
  // off, a new tool length under TRAORI, the program end).
  void observe(const CanonCall& call);

  const Vec5& current() const { return cur_; }
  bool tcp() const { return tcp_; }
  // Re-expresses the current point for the tool now in use (TRAORI only).
  void rebase(const CallContext& ctx);

  Vec5 to_planning(const Axes6& program, const CallContext& ctx) const;
  // Program coordinates (program units, degrees) of a planning point.
  Axes6 to_program(const Vec5& p, const CallContext& ctx) const;
  // Tip and tool axis in the workpiece frame.
  ToolPoint tool_point(const Vec5& p, const CallContext& ctx) const;
  // The planning point whose tip is shifted by `shift_mm` (workpiece
  // frame) with A and C unchanged.
  Vec5 shifted(const Vec5& p, const CallContext& ctx, const Eigen::Vector3d& shift_mm) const;
  // The planning point whose tip is shifted by `shift_mm` and whose tool is
  // turned about it by `rotation_rad` (a rotation vector, workpiece frame),
  // as truecut_comp does in joint mode (rt::comp::rotary_correction: A and
  // C by least squares, damped where A is near 0, each at most
  // rt::comp::kDefaultMaxRotaryCorrectionDeg); `shortfall_rad` gets what
  // they could not give.
  Vec5 corrected(const Vec5& p, const CallContext& ctx, const Eigen::Vector3d& shift_mm,
                 const Eigen::Vector3d& rotation_rad, double& shortfall_rad) const;

  // Points of the move from current() at fractions k/n, k = 1..n, and the
  // point at a fraction in [0, 1].
  struct Move {
    bool arc = false;
    Vec5 start{}, end{};
    // arc: its plane axes, and the arc in their coordinates
    path_geometry::PlaneAxes axes;
    path_geometry::PlaneArc plane;
    // an arc under a rotated coordinate system: `plane` is in the frame
    // turned back by rotation_deg about Z after removing offset_mm (G5x,
    // and the tool length outside TRAORI), where its ends are turned_*
    double rotation_deg = 0;
    std::array<double, 3> offset_mm{};
    Vec5 turned_start{}, turned_end{};
  };
  Move line_to(const Axes6& end, const CallContext& ctx) const;
  Move arc_to(const ArcFeed& arc, const CallContext& ctx) const;
  static Vec5 at(const Move& m, double fraction);
  void finish(const Move& m) { cur_ = m.end; }

 private:
  rt::AcTrtParams kinematics(const CallContext& ctx) const;
  void set_tcp(bool on, const CallContext& ctx);

  rt::AcTrtParams base_;
  bool tcp_ = false;
  double tcp_tool_length_mm_ = 0;
  Vec5 cur_{};
};

}  // namespace truecut::interp::rewrite
