// Per-axis kinematic limits of the X Y Z A C machine the planner respects on
// every servo cycle. Linear axes in mm, rotary axes in degrees.
#pragma once

#include <array>

namespace truecut::interp {

enum Axis { kAxisX = 0, kAxisY, kAxisZ, kAxisA, kAxisC, kAxisCount };

struct AxisLimits {
  double max_velocity = 0;      // mm/s or deg/s
  double max_acceleration = 0;  // mm/s^2 or deg/s^2
  double max_jerk = 0;          // mm/s^3 or deg/s^3
};

struct MachineLimits {
  std::array<AxisLimits, kAxisCount> axis{{
      {200.0, 2000.0, 50000.0},  // X
      {200.0, 2000.0, 50000.0},  // Y
      {200.0, 2000.0, 50000.0},  // Z
      {90.0, 900.0, 20000.0},    // A
      {180.0, 1800.0, 40000.0},  // C
  }};
};

}  // namespace truecut::interp
