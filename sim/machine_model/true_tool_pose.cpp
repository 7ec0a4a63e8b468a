#include "truecut/sim/true_tool_pose.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

namespace truecut::sim {

namespace {

constexpr double kRadPerDeg = std::numbers::pi / 180.0;

using Vec = Eigen::Vector3d;

Vec vec(const std::array<double, 3>& a) noexcept {
  return {a[0], a[1], a[2]};
}
std::array<double, 3> arr(const Vec& v) noexcept {
  return {v.x(), v.y(), v.z()};
}

// Rodrigues: the right-handed rotation of v by `angle_rad` about the unit u.
Vec rotate(const Vec& u, double angle_rad, const Vec& v) noexcept {
  const double c = std::cos(angle_rad), s = std::sin(angle_rad);
  return v * c + u.cross(v) * s + u * (u.dot(v) * (1.0 - c));
}

// As rt::forward_ac: reduce to [-180, 180] first, so that many turns of C
// lose no precision.
double to_rad(double deg) noexcept {
  // remainder() of glibc is slow, and within [-180, 180] it is the identity
  // (a tie at 180 rounds to the even quotient 0).
  if (std::fabs(deg) <= 180.0) return deg * kRadPerDeg;
  return std::remainder(deg, 360.0) * kRadPerDeg;
}

}  // namespace

rt::AcTrtParams nominal_ac_params(const MachineParams& m) noexcept {
  const KinematicsParams& k = m.kinematics;
  rt::AcTrtParams p = k.ac;
  p.tool_length_mm = k.tool.length_mm;
  if (m.joints[kA].present) {
    p.a_min_deg = m.joints[kA].min;
    p.a_max_deg = m.joints[kA].max;
  }
  return p;
}

TrueTool true_tool(const MachineParams& m) noexcept {
  return true_tool(m.kinematics.tool, m.effects);
}

TrueTool true_tool(const NominalTool& n, const Effects& effects) noexcept {
  TrueTool t{n.length_mm, n.radius_mm, n.corner_radius_mm};
  if (const auto* e = effects.tool_length_error.active()) t.length_mm += e->length_mm;
  if (const auto* e = effects.tool_radius_error.active()) {
    t.radius_mm += e->radius_mm;
    t.corner_radius_mm =
        is_ball_end_mill(n) ? t.radius_mm : n.corner_radius_mm + e->corner_radius_mm;
  }
  return t;
}

TrueKinematics true_kinematics(const MachineParams& m) noexcept {
  const KinematicsParams& k = m.kinematics;
  TrueKinematics t;
  t.a_point_mm = {k.ac.x_rot_point_mm, k.ac.y_rot_point_mm + k.ac.y_offset_mm,
                  k.ac.z_rot_point_mm + k.ac.z_offset_mm};
  t.c_point_mm = {k.ac.x_rot_point_mm, k.ac.y_rot_point_mm, k.ac.z_rot_point_mm};
  t.conventional_directions = k.ac.conventional_directions;
  t.tool_length_mm = true_tool(m).length_mm;
  if (const auto* r = m.effects.rotary_location.active()) {
    t.a_point_mm[1] += r->a.e_y0a_um * 1e-3;
    t.a_point_mm[2] += r->a.e_z0a_um * 1e-3;
    t.a_direction = arr(Vec(1.0, r->a.e_c0a_urad * 1e-6, -r->a.e_b0a_urad * 1e-6).normalized());
    t.a_zero_rad = r->a.e_a0a_urad * 1e-6;
    t.c_point_mm[0] += r->c.e_x0c_um * 1e-3;
    t.c_point_mm[1] += r->c.e_y0c_um * 1e-3;
    t.c_direction = arr(Vec(r->c.e_b0c_urad * 1e-6, -r->c.e_a0c_urad * 1e-6, 1.0).normalized());
    t.c_zero_rad = r->c.e_c0c_urad * 1e-6;
  }
  return t;
}

rt::ToolPose true_tool_pose(const TrueKinematics& k, const std::array<double, 3>& xyz_true_mm,
                            double a_true_deg, double c_true_deg) noexcept {
  const double sigma = k.conventional_directions ? -1.0 : 1.0;
  const double alpha = sigma * (to_rad(a_true_deg) + k.a_zero_rad);
  const double gamma = sigma * (to_rad(c_true_deg) + k.c_zero_rad);
  const Vec qa = vec(k.a_point_mm), qc = vec(k.c_point_mm);
  const Vec ua = vec(k.a_direction), uc = vec(k.c_direction);
  const Vec tcp_machine{xyz_true_mm[0], xyz_true_mm[1], xyz_true_mm[2] - k.tool_length_mm};

  rt::ToolPose pose;
  pose.tcp_mm = qc + rotate(uc, -gamma, rotate(ua, -alpha, tcp_machine - qa) + (qa - qc));
  pose.axis = rotate(uc, -gamma, rotate(ua, -alpha, Vec::UnitZ()));
  return pose;
}

}  // namespace truecut::sim
