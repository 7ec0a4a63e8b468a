// rotary_location: the location errors of the A and C axis lines (ISO 230-7).
// The real axis lines of the trunnion (A) and of the table (C) sit a little
// away from where the nominal kinematics puts them, lean a little, and the
// angles start from a slightly wrong zero:
//
//   A (nominal: through P_A = (x_rot, y_rot + y_offset, z_rot + z_offset), along +X)
//     through  Q_A = P_A + (0, E_Y0A, E_Z0A)
//     along    u_A = (1, E_C0A, −E_B0A) / |·|
//     turned   by A + E_A0A
//   C (nominal: through P_C = (x_rot, y_rot, z_rot), along +Z, in the cradle frame)
//     through  Q_C = P_C + (E_X0C, E_Y0C, 0)
//     along    u_C = (E_B0C, −E_A0C, 1) / |·|
//     turned   by C + E_C0C
//
// Offsets in µm, tilts and zero offsets in µrad (as squareness). A tilt is a
// right-handed rotation of the axis line about the named machine axis,
// pivoting at Q_A (for A) or at the height z_rot_point (for C); a zero
// offset is the true angle minus the reading, in the joint's own direction.
// The rotations about the tilted lines are exact (Rodrigues); the
// equations are in docs/machine-model.md and the transform in
// true_tool_pose.hpp.
#pragma once

namespace truecut::sim {

struct RotaryLocationA {
  double e_y0a_um = 0.0;    // position of the A axis line in Y
  double e_z0a_um = 0.0;    // position of the A axis line in Z
  double e_b0a_urad = 0.0;  // tilt of the A axis line about Y (in XZ)
  double e_c0a_urad = 0.0;  // tilt of the A axis line about Z (in XY)
  double e_a0a_urad = 0.0;  // zero-angle offset of A
  bool operator==(const RotaryLocationA&) const = default;
};

struct RotaryLocationC {
  double e_x0c_um = 0.0;    // position of the C axis line in X
  double e_y0c_um = 0.0;    // position of the C axis line in Y
  double e_a0c_urad = 0.0;  // tilt of the C axis line about X (in YZ)
  double e_b0c_urad = 0.0;  // tilt of the C axis line about Y (in XZ)
  double e_c0c_urad = 0.0;  // zero-angle offset of C
  bool operator==(const RotaryLocationC&) const = default;
};

struct RotaryLocationParams {
  RotaryLocationA a;
  RotaryLocationC c;
  bool operator==(const RotaryLocationParams&) const = default;
};

}  // namespace truecut::sim
