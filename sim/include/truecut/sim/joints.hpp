// The joints of the simulated A/C table-table machine and their units.
#pragma once

#include <array>
#include <string_view>

namespace truecut::sim {

inline constexpr int kJointCount = 5;
enum JointIndex : int { kX = 0, kY = 1, kZ = 2, kA = 3, kC = 4 };
inline constexpr std::array<std::string_view, kJointCount> kJointNames = {"x", "y", "z", "a", "c"};

enum class JointKind { kLinear, kRotary };

// X, Y, Z are linear (mm); A and C are rotary (degrees).
constexpr JointKind joint_kind(int joint) {
  return joint < 3 ? JointKind::kLinear : JointKind::kRotary;
}
constexpr std::string_view joint_unit(int joint) {
  return joint_kind(joint) == JointKind::kLinear ? "mm" : "deg";
}

}  // namespace truecut::sim
