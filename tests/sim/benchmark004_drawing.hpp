// benchmark004 as drawn (docs/parts.md), independent of the generator's
// constants, and the coarse options its tests run at.
#pragma once

#include <Eigen/Core>

#include "truecut/sim/benchmark_parts.hpp"

namespace truecut::sim::test::benchmark004 {

constexpr double kBaseR = 50, kStep1Z = 15, kStepR = 40, kStep2Z = 30, kCollarR = 20, kSphereZ = 35,
                 kSphereR = 20;
inline const Eigen::Vector3d kSphereCentre(0, 0, kSphereZ);

inline PartOptions coarse() {
  return {2.0, 0.8, 1.0, 2.0};
}

}  // namespace truecut::sim::test::benchmark004
