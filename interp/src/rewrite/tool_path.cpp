#include "tool_path.hpp"

#include "truecut/rt/core/joint_mode.hpp"

#include <cmath>

namespace truecut::interp::rewrite {

rt::AcTrtParams ToolPath::kinematics(const CallContext& ctx) const {
  rt::AcTrtParams k = base_;
  k.tool_length_mm += ctx.tool_offset_mm.z;
  return k;
}

Vec5 ToolPath::to_planning(const Axes6& p, const CallContext& ctx) const {
  const Axes6 m = machine_position_mm(p, ctx);
  Vec5 r{m.x, m.y, m.z, m.a, m.c};
  if (tcp_)
    for (int i = 0; i < 3; ++i)
      r[i] -= ctx.tool_offset_mm[i];
  return r;
}

Axes6 ToolPath::to_program(const Vec5& p, const CallContext& ctx) const {
  const double scale = ctx.units == LengthUnits::kInch ? 25.4 : 1.0;
  // The inverse of machine_position_mm: machine XY = G5x + rotation ×
  // (program + G92) + tool.
  double v[3];
  for (int i = 0; i < 3; ++i)
    v[i] = p[i] - ctx.g5x_mm[i] - (tcp_ ? 0.0 : ctx.tool_offset_mm[i]);
  if (ctx.xy_rotation_deg != 0) rotate_xy_deg(v[0], v[1], -ctx.xy_rotation_deg);
  Axes6 out;
  for (int i = 0; i < 3; ++i)
    out[i] = (v[i] - ctx.g92_mm[i]) / scale;
  out.a = p[3] - ctx.g5x_mm.a - ctx.g92_mm.a - ctx.tool_offset_mm.a;
  out.c = p[4] - ctx.g5x_mm.c - ctx.g92_mm.c - ctx.tool_offset_mm.c;
  return out;
}

ToolPoint ToolPath::tool_point(const Vec5& p, const CallContext& ctx) const {
  const rt::AcTrtParams k = kinematics(ctx);
  if (tcp_) {
    const rt::ToolPose pose = rt::forward_ac(k, rt::AcJoints{0, 0, 0, p[3], p[4]});
    return {Eigen::Vector3d(p[0], p[1], p[2]), pose.axis};
  }
  const rt::ToolPose pose = rt::forward_ac(k, rt::AcJoints{p[0], p[1], p[2], p[3], p[4]});
  return {pose.tcp_mm, pose.axis};
}

Vec5 ToolPath::shifted(const Vec5& p, const CallContext& ctx,
                       const Eigen::Vector3d& shift_mm) const {
  Vec5 out = p;
  if (tcp_) {
    for (int i = 0; i < 3; ++i)
      out[i] += shift_mm[i];
    return out;
  }
  // For fixed A and C the tip is an affine function of X Y Z with an
  // orthonormal linear part R: joints move by R^T * shift.
  const rt::AcTrtParams k = kinematics(ctx);
  const rt::AcJoints j{p[0], p[1], p[2], p[3], p[4]};
  const Eigen::Vector3d t0 = rt::forward_ac(k, j).tcp_mm;
  Eigen::Matrix3d r;
  for (int i = 0; i < 3; ++i) {
    rt::AcJoints ji = j;
    (i == 0 ? ji.x_mm : i == 1 ? ji.y_mm : ji.z_mm) += 1.0;
    r.col(i) = rt::forward_ac(k, ji).tcp_mm - t0;
  }
  const Eigen::Vector3d d = r.transpose() * shift_mm;
  for (int i = 0; i < 3; ++i)
    out[i] += d[i];
  return out;
}

Vec5 ToolPath::corrected(const Vec5& p, const CallContext& ctx, const Eigen::Vector3d& shift_mm,
                         const Eigen::Vector3d& rotation_rad, double& shortfall_rad) const {
  shortfall_rad = 0.0;
  if (rotation_rad.isZero(0.0)) return shifted(p, ctx, shift_mm);
  const rt::AcTrtParams k = kinematics(ctx);
  const rt::comp::JointLimits limits;  // A and C at their default bounds, X Y Z free
  if (tcp_) {
    // Under TRAORI X Y Z are the tip: A and C turn, the tip is shifted.
    const rt::AcJoints j{0.0, 0.0, 0.0, p[3], p[4]};
    rt::ToolPose pose = rt::forward_ac(k, j);
    pose.tcp_mm = tool_point(p, ctx).tip_mm;
    const rt::comp::RotaryCorrection rc =
        rt::comp::rotary_correction(k, j, pose, rotation_rad, limits);
    shortfall_rad = rc.shortfall_rad;
    Vec5 out = p;
    for (int i = 0; i < 3; ++i)
      out[i] += shift_mm[i];
    out[3] += rc.da_deg;
    out[4] += rc.dc_deg;
    return out;
  }
  const rt::AcJoints j{p[0], p[1], p[2], p[3], p[4]};
  const rt::ToolPose pose = rt::forward_ac(k, j);
  const rt::comp::RotaryCorrection rc =
      rt::comp::rotary_correction(k, j, pose, rotation_rad, limits);
  shortfall_rad = rc.shortfall_rad;
  const rt::AcJoints out = rt::comp::correct_joints(k, j, pose, shift_mm, rc);
  return {out.x_mm, out.y_mm, out.z_mm, out.a_deg, out.c_deg};
}

void ToolPath::rebase(const CallContext& ctx) {
  if (!tcp_) return;
  const rt::AcTrtParams kin = kinematics(ctx);
  if (kin.tool_length_mm == tcp_tool_length_mm_) return;
  rt::AcTrtParams old = kin;
  old.tool_length_mm = tcp_tool_length_mm_;
  const rt::ToolPose pose_old = rt::forward_ac(old, rt::AcJoints{0, 0, 0, cur_[3], cur_[4]});
  rt::ToolPose tip_old{Eigen::Vector3d(cur_[0], cur_[1], cur_[2]), pose_old.axis};
  const rt::AcJoints joints =
      rt::inverse_ac(old, tip_old, rt::AcJoints{0, 0, 0, cur_[3], cur_[4]}).joints;
  const rt::ToolPose pose = rt::forward_ac(kin, joints);
  cur_ = {pose.tcp_mm.x(), pose.tcp_mm.y(), pose.tcp_mm.z(), cur_[3], cur_[4]};
  tcp_tool_length_mm_ = kin.tool_length_mm;
}

void ToolPath::set_tcp(bool on, const CallContext& ctx) {
  if (on == tcp_) return;
  rebase(ctx);
  const rt::AcTrtParams kin = kinematics(ctx);
  if (on) {
    const rt::ToolPose pose =
        rt::forward_ac(kin, rt::AcJoints{cur_[0], cur_[1], cur_[2], cur_[3], cur_[4]});
    cur_ = {pose.tcp_mm.x(), pose.tcp_mm.y(), pose.tcp_mm.z(), cur_[3], cur_[4]};
  } else {
    const rt::ToolPose axis = rt::forward_ac(kin, rt::AcJoints{0, 0, 0, cur_[3], cur_[4]});
    const rt::ToolPose tip{Eigen::Vector3d(cur_[0], cur_[1], cur_[2]), axis.axis};
    const rt::AcJoints j = rt::inverse_ac(kin, tip, rt::AcJoints{0, 0, 0, cur_[3], cur_[4]}).joints;
    cur_ = {j.x_mm, j.y_mm, j.z_mm, cur_[3], cur_[4]};
  }
  tcp_ = on;
  tcp_tool_length_mm_ = kin.tool_length_mm;
}

void ToolPath::observe(const CanonCall& c) {
  if (const auto* t = std::get_if<SetTcp>(&c.op)) set_tcp(t->on, c.context);
  if (std::holds_alternative<ProgramEnd>(c.op)) set_tcp(false, c.context);
}

ToolPath::Move ToolPath::line_to(const Axes6& end, const CallContext& ctx) const {
  Move m;
  m.start = cur_;
  m.end = to_planning(end, ctx);
  return m;
}

ToolPath::Move ToolPath::arc_to(const ArcFeed& arc, const CallContext& ctx) const {
  Move m;
  m.arc = true;
  m.start = cur_;
  m.end = to_planning(arc.end, ctx);
  m.axes = path_geometry::plane_axes(arc.plane);
  const int first = m.axes.first, second = m.axes.second;
  Axes6 cprog = arc.end;
  cprog[first] = arc.center[first];
  cprog[second] = arc.center[second];
  Vec5 centre = to_planning(cprog, ctx);
  Vec5 start = m.start, end = m.end;
  // A rotated coordinate system (G10 L2 R) turns the arc's plane about Z:
  // the arc is built in the frame turned back, as the planner does, and
  // its points turned forward (see at()).
  if (ctx.xy_rotation_deg != 0) {
    m.rotation_deg = ctx.xy_rotation_deg;
    for (int i = 0; i < 3; ++i)
      m.offset_mm[i] = ctx.g5x_mm[i] + (tcp_ ? 0.0 : ctx.tool_offset_mm[i]);
    for (Vec5* v : {&start, &end, &centre}) {
      for (int i = 0; i < 3; ++i)
        (*v)[i] -= m.offset_mm[i];
      rotate_xy_deg((*v)[0], (*v)[1], -m.rotation_deg);
    }
    m.turned_start = start;
    m.turned_end = end;
  }
  m.plane = path_geometry::plane_arc(start[first], start[second], end[first], end[second],
                                     centre[first], centre[second], arc.rotation);
  return m;
}

Vec5 ToolPath::at(const Move& m, double f) {
  if (f >= 1.0) return m.end;
  if (!m.arc) return path_geometry::line_point_at(m.start, m.end, f, 5);
  if (m.rotation_deg == 0)
    return path_geometry::arc_point_at(m.axes, m.plane, m.start, m.end, f, 5);
  Vec5 p = path_geometry::arc_point_at(m.axes, m.plane, m.turned_start, m.turned_end, f, 5);
  rotate_xy_deg(p[0], p[1], m.rotation_deg);
  for (int i = 0; i < 3; ++i)
    p[i] += m.offset_mm[i];
  return p;
}

}  // namespace truecut::interp::rewrite
