#include "truecut/rt/core/kinematics_ac.hpp"

#include <cmath>
#include <numbers>

namespace truecut::rt {
namespace {

constexpr double kRadPerDeg = std::numbers::pi / 180.0;
constexpr double kDegPerRad = 180.0 / std::numbers::pi;

// Degrees to radians after reducing to [-180, 180] (exact), so that many
// turns of C lose no precision.
double to_rad(double deg) noexcept {
  // remainder() of glibc is slow, and within [-180, 180] it is the identity
  // (a tie at 180 rounds to the even quotient 0).
  if (std::fabs(deg) <= 180.0) return deg * kRadPerDeg;
  return std::remainder(deg, 360.0) * kRadPerDeg;
}

// Right-handed rotations by `angle_rad` about +X and +Z.
Eigen::Vector3d rot_x(double angle_rad, const Eigen::Vector3d& v) noexcept {
  const double c = std::cos(angle_rad), s = std::sin(angle_rad);
  return {v.x(), c * v.y() - s * v.z(), s * v.y() + c * v.z()};
}
Eigen::Vector3d rot_z(double angle_rad, const Eigen::Vector3d& v) noexcept {
  const double c = std::cos(angle_rad), s = std::sin(angle_rad);
  return {c * v.x() - s * v.y(), s * v.x() + c * v.y(), v.z()};
}

// +1: joint angle = table rotation (LinuxCNC default); -1: ISO 841.
double direction(const AcTrtParams& p) noexcept {
  return p.conventional_directions ? -1.0 : 1.0;
}

Eigen::Vector3d c_pivot(const AcTrtParams& p) noexcept {
  return {p.x_rot_point_mm, p.y_rot_point_mm, p.z_rot_point_mm};
}
Eigen::Vector3d a_pivot(const AcTrtParams& p) noexcept {
  return {p.x_rot_point_mm, p.y_rot_point_mm + p.y_offset_mm, p.z_rot_point_mm + p.z_offset_mm};
}

bool finite(const AcJoints& j) noexcept {
  return std::isfinite(j.x_mm) && std::isfinite(j.y_mm) && std::isfinite(j.z_mm) &&
         std::isfinite(j.a_deg) && std::isfinite(j.c_deg);
}

// The multiple of 360 degrees added to `c_deg` that brings it closest to `near_deg`.
double unwind(double c_deg, double near_deg) noexcept {
  return c_deg + 360.0 * std::round((near_deg - c_deg) / 360.0);
}

struct Candidate {
  double a_deg;
  double c_deg;
  bool in_travel;
  double distance2;  // to the hint, deg^2
};

Candidate make_candidate(const AcTrtParams& p, const AcJoints& hint, double a_deg,
                         double c_deg) noexcept {
  Candidate k{a_deg, unwind(c_deg, hint.c_deg), false, 0.0};
  k.in_travel = k.a_deg >= p.a_min_deg && k.a_deg <= p.a_max_deg;
  const double da = k.a_deg - hint.a_deg, dc = k.c_deg - hint.c_deg;
  k.distance2 = da * da + dc * dc;
  return k;
}

}  // namespace

const char* to_string(AcIkStatus status) noexcept {
  switch (status) {
    case AcIkStatus::kOk:
      return "ok";
    case AcIkStatus::kSingular:
      return "singular";
    case AcIkStatus::kOutOfLimits:
      return "out_of_limits";
    case AcIkStatus::kInvalidInput:
      return "invalid_input";
  }
  return "unknown";
}

ToolPose forward_ac(const AcTrtParams& p, const AcJoints& j) noexcept {
  const double sigma = direction(p);
  const double alpha = sigma * to_rad(j.a_deg);  // table rotation about +X
  const double gamma = sigma * to_rad(j.c_deg);  // table rotation about +Z
  const Eigen::Vector3d pc = c_pivot(p), pa = a_pivot(p);
  const Eigen::Vector3d tcp_machine{j.x_mm, j.y_mm, j.z_mm - p.tool_length_mm};

  ToolPose pose;
  pose.tcp_mm = pc + rot_z(-gamma, rot_x(-alpha, tcp_machine - pa) + (pa - pc));
  pose.axis = rot_z(-gamma, rot_x(-alpha, Eigen::Vector3d::UnitZ()));
  return pose;
}

AcIkResult inverse_ac(const AcTrtParams& p, const ToolPose& pose, const AcJoints& hint) noexcept {
  AcIkResult result{hint, AcIkStatus::kInvalidInput};
  const double axis_norm = pose.axis.norm();
  if (!pose.tcp_mm.allFinite() || !std::isfinite(axis_norm) || axis_norm == 0.0 || !finite(hint))
    return result;
  const Eigen::Vector3d n = pose.axis / axis_norm;
  const double sigma = direction(p);

  // Table angles (alpha, gamma) satisfy n = (sin a sin g, sin a cos g, cos a).
  const double tilt_sin = std::hypot(n.x(), n.y());
  Candidate chosen{};
  // sin(x) <= x for x >= 0 (also as computed: x is a double), so a tilt
  // beyond x itself, as of nearly every pose, needs no sine; the choice is
  // the same as with it (the sine was a twentieth of the planner's time).
  const double singular_rad = p.singular_tilt_deg * kRadPerDeg;
  if (tilt_sin < singular_rad && tilt_sin < std::sin(singular_rad)) {
    // C is undefined: keep the hint's C and tilt within its plane.
    const double gamma = sigma * to_rad(hint.c_deg);
    const double alpha = std::atan2(n.x() * std::sin(gamma) + n.y() * std::cos(gamma), n.z());
    chosen = make_candidate(p, hint, sigma * alpha * kDegPerRad, hint.c_deg);
    result.status = chosen.in_travel ? AcIkStatus::kSingular : AcIkStatus::kOutOfLimits;
  } else {
    const double alpha = std::atan2(tilt_sin, n.z());  // in [0, pi]
    const double gamma = std::atan2(n.x(), n.y());
    const Candidate k1 =
        make_candidate(p, hint, sigma * alpha * kDegPerRad, sigma * gamma * kDegPerRad);
    const Candidate k2 =
        make_candidate(p, hint, -sigma * alpha * kDegPerRad, sigma * gamma * kDegPerRad + 180.0);
    if (k1.in_travel != k2.in_travel)
      chosen = k1.in_travel ? k1 : k2;
    else
      chosen = k1.distance2 <= k2.distance2 ? k1 : k2;
    result.status = chosen.in_travel ? AcIkStatus::kOk : AcIkStatus::kOutOfLimits;
  }

  const double alpha = sigma * to_rad(chosen.a_deg);
  const double gamma = sigma * to_rad(chosen.c_deg);
  const Eigen::Vector3d pc = c_pivot(p), pa = a_pivot(p);
  const Eigen::Vector3d tcp_machine = pa + rot_x(alpha, rot_z(gamma, pose.tcp_mm - pc) + (pc - pa));
  result.joints = {tcp_machine.x(), tcp_machine.y(), tcp_machine.z() + p.tool_length_mm,
                   chosen.a_deg, chosen.c_deg};
  return result;
}

}  // namespace truecut::rt
