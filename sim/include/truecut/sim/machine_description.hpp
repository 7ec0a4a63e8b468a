// The machine description: joints (travel, drive parameters), the nominal
// kinematics and tool, and the switchable physics effects of the simulated
// machine (joint errors, geometric errors, tool errors, tool and workpiece
// deflection under the cutting force), read from and written
// to JSON (`truecut_machine: 1`, see docs/formats.md). With every effect off
// the machine is ideal: actual = commanded.
//
// Everything in MachineParams is plain data (trivially copyable), so a servo
// component can hold a copy in memory the HAL owns.
#pragma once

#include <array>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>

#include "truecut/sim/effects/backlash.hpp"
#include "truecut/sim/effects/geometric_errors.hpp"
#include "truecut/sim/effects/pitch_error.hpp"
#include "truecut/sim/effects/reversal_spike.hpp"
#include "truecut/sim/effects/rotary_location.hpp"
#include "truecut/sim/effects/servo_lag.hpp"
#include "truecut/sim/effects/thermal_drift.hpp"
#include "truecut/sim/effects/tool_deflection.hpp"
#include "truecut/sim/effects/tool_length_error.hpp"
#include "truecut/sim/effects/tool_radius_error.hpp"
#include "truecut/sim/effects/workpiece_deflection.hpp"
#include "truecut/sim/joints.hpp"
#include "truecut/sim/machine_kinematics.hpp"

namespace truecut::sim {

// The drive of a joint, used when servo_lag is on for it. Values are in the
// joint's unit (mm or deg).
struct DriveParams {
  double vel_bandwidth_hz = 40.0;      // velocity-loop crossover f_v: Kp = 2π f_v
  double vel_integral_time_s = 0.01;   // velocity-loop integral time T_n: Ki = Kp / T_n
  double inertia = 500.0;              // kg (linear, incl. reflected rotor) or kg·m² (rotary)
  double max_accel = 5000.0;           // acceleration (force) limit, unit/s²
  double encoder_resolution = 0.0001;  // unit per count; 0: unquantised
  bool operator==(const DriveParams&) const = default;
};

struct JointParams {
  bool present = false;  // listed in the description; an absent joint has travel [0, 0]
  double min = 0.0;      // travel, mm or deg
  double max = 0.0;
  DriveParams drive;
  bool operator==(const JointParams&) const = default;
};

// Defaults of a joint listed without a `drive` object.
DriveParams default_drive(int joint);

template <class Axis>
struct PerAxisEffect {
  bool enabled = false;
  std::array<std::optional<Axis>, kJointCount> axes;
  // The parameters in force for a joint: null when the effect is off, the
  // joint is not listed or not a joint (−1: an effect of no axis).
  const Axis* active(int joint) const noexcept {
    if (!enabled || joint < 0 || joint >= kJointCount) return nullptr;
    return axes[static_cast<std::size_t>(joint)] ? &*axes[static_cast<std::size_t>(joint)]
                                                 : nullptr;
  }
  bool operator==(const PerAxisEffect&) const = default;
};

template <class Params>
struct GlobalEffect {
  bool enabled = false;
  Params params;
  const Params* active() const noexcept { return enabled ? &params : nullptr; }
  bool operator==(const GlobalEffect&) const = default;
};

struct Effects {
  PerAxisEffect<ServoLagAxis> servo_lag;
  PerAxisEffect<BacklashAxis> backlash;
  PerAxisEffect<ReversalSpikeAxis> reversal_spike;
  PerAxisEffect<PitchErrorAxis> pitch_error;      // x, y, z only
  PerAxisEffect<ThermalDriftAxis> thermal_drift;  // x, y, z only
  GlobalEffect<SquarenessParams> squareness;
  GlobalEffect<StraightnessParams> straightness;
  GlobalEffect<RotaryLocationParams> rotary_location;
  GlobalEffect<ToolLengthErrorParams> tool_length_error;
  GlobalEffect<ToolRadiusErrorParams> tool_radius_error;
  GlobalEffect<ToolDeflectionParams> tool_deflection;
  GlobalEffect<WorkpieceDeflectionParams> workpiece_deflection;
  bool operator==(const Effects&) const = default;
};

// The effect names as the JSON file spells them, in the order above.
inline constexpr std::array<const char*, 12> kEffectNames = {
    "servo_lag",         "backlash",          "reversal_spike",  "pitch_error",
    "thermal_drift",     "squareness",        "straightness",    "rotary_location",
    "tool_length_error", "tool_radius_error", "tool_deflection", "workpiece_deflection"};

struct MachineParams {
  std::array<JointParams, kJointCount> joints;
  KinematicsParams kinematics;  // nominal; defaults: all zeros
  Effects effects;
  bool operator==(const MachineParams&) const = default;
};
static_assert(std::is_trivially_copyable_v<MachineParams>);

struct MachineDescription {
  std::string name;  // free text
  MachineParams machine;
  bool operator==(const MachineDescription&) const = default;
};

// Bad input: the message is "FILE: key.path: what is wrong".
class MachineDescriptionError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// `file_name` is used in messages only.
MachineDescription parse_machine_description(const std::string& json_text,
                                             const std::string& file_name);
MachineDescription read_machine_description(const std::filesystem::path& file);

// Every joint listed and every effect that is on or has parameters, all
// parameters explicit; parsing the text gives the same description back.
std::string format_machine_description(const MachineDescription& description);
// Atomic: written as FILE.tmp, then renamed.
void write_machine_description(const std::filesystem::path& file,
                               const MachineDescription& description);

}  // namespace truecut::sim
