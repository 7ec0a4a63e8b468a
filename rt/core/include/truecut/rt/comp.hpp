// The real-time core of truecut: everything the compensation does inside the
// servo cycle, and nothing else. One include for a controller module (a
// LinuxCNC HAL module built with halcompile, truecut's own truecut_comp.so):
//
//   #include "truecut/rt/comp.hpp"      include path: rt/core/include
//   compile also rt/core/src/*.cpp      needs: the C++20 standard library, Eigen
//
// It brings
// - truecut::rt::CorrectionField (core/correction_field.hpp): the field and
//   its per-cycle evaluation;
// - truecut::rt::forward_ac / inverse_ac (core/kinematics_ac.hpp): the A/C
//   table-table kinematics, as LinuxCNC's xyzac-trt-kins;
// - truecut::rt::comp (core/comp_math.hpp, core/comp_core.hpp,
//   core/joint_mode.hpp): one cycle of the compensation, comp::step(), its
//   limits (comp::CompLimits, comp::kDefaultMaxCorrectionMm) and the
//   joint-space mode.
// Nothing here touches the HAL, files or threads: the caller reads its pins,
// calls comp::step() and writes its pins (rt/components/truecut_comp/ is
// truecut's HAL edge), and builds a CorrectionField outside the servo thread
// (truecut reads .tcf files with rt/include/truecut/rt/field_file.hpp).
// Servo-cycle functions are noexcept and neither allocate, lock nor do I/O.
#pragma once

#include "truecut/rt/core/comp_core.hpp"
#include "truecut/rt/core/comp_math.hpp"
#include "truecut/rt/core/correction_field.hpp"
#include "truecut/rt/core/joint_mode.hpp"
#include "truecut/rt/core/kinematics_ac.hpp"
