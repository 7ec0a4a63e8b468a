#include "system_parameters.hpp"

#include <string>

namespace truecut::interp {

void sync_state_parameters(const InterpState& state, Parameters& params) {
  params.set(kCoordSystemIndex, state.coord_index);
  params.set(5400, state.tool);
  // #5401..#5413 (the loaded tool's row) are written on M6 and G10 L1
  // (BlockExecutor::loaded_tool_parameters).
  const Axes6 pos = state.program_position();
  for (int i = 0; i < 6; ++i)
    params.set(5420 + i, pos[i]);
}

std::optional<double> predefined_parameter(const InterpState& s, const Parameters& params,
                                           std::string_view name) {
  if (name.empty() || name[0] != '_') return std::nullopt;
  const std::string_view n = name.substr(1);
  const Axes6 pos = s.program_position();
  static const char* kAxes[] = {"x", "y", "z", "a", "b", "c"};
  for (int i = 0; i < 6; ++i)
    if (n == kAxes[i]) return pos[i];
  // #<_abs_x> ...: the position in machine coordinates (where a G53 move
  // to it would go), in program units.
  if (n.size() == 5 && n.substr(0, 4) == "abs_")
    for (int i = 0; i < 6; ++i)
      if (n[4] == kAxes[i][0]) return s.to_program(i, s.position_mm[i]);
  auto flag = [](bool b) { return b ? 1.0 : 0.0; };
  if (n == "metric") return flag(s.units == LengthUnits::kMm);
  if (n == "imperial") return flag(s.units == LengthUnits::kInch);
  if (n == "absolute") return flag(!s.incremental);
  if (n == "incremental") return flag(s.incremental);
  if (n == "inverse_time") return flag(s.feed_mode == FeedMode::kInverseTime);
  if (n == "units_per_minute") return flag(s.feed_mode == FeedMode::kUnitsPerMinute);
  if (n == "units_per_rev") return flag(s.feed_mode == FeedMode::kUnitsPerRevolution);
  if (n == "coord_system") {
    static const double kCodes[] = {540, 550, 560, 570, 580, 590, 591, 592, 593};
    return kCodes[s.coord_index - 1];
  }
  if (n == "tool_offset") return flag(s.tool_offset_mm != Axes6{});
  if (n == "feed") return s.feed;
  if (n == "rpm") return s.speed;
  if (n == "current_tool") return static_cast<double>(s.tool);
  if (n == "selected_tool") return static_cast<double>(s.selected_tool);
  if (n == "current_pocket" || n == "selected_pocket") return 0.0;
  if (n == "spindle_on") return flag(s.spindle != 0);
  if (n == "spindle_cw") return flag(s.spindle > 0);
  if (n == "mist") return flag(s.mist);
  if (n == "flood") return flag(s.flood);
  if (n == "plane") {
    switch (s.plane) {
      case Plane::kXY:
        return 170.0;
      case Plane::kXZ:
        return 180.0;
      case Plane::kYZ:
        return 190.0;
    }
  }
  if (n == "motion_mode") {
    if (s.motion == kMotionNone) return -1;  // after G5.3, as rs274
    return s.motion >= 0 && s.motion < 10000 ? s.motion : 10.0;
  }
  if (n == "call_level") return static_cast<double>(params.call_level());
  if (n == "remap_level") return 0.0;
  if (n == "task") return 0.0;  // not running under a controller task
  if (n == "line") return static_cast<double>(s.line);
  if (n == "vmajor") return 2.9;  // the LinuxCNC language version followed
  if (n == "vminor") return 0.0;
  if (n == "ccomp") return 400.0;
  if (n == "retract_r_plane") return flag(!s.retract_old_z);
  if (n == "retract_old_z") return flag(s.retract_old_z);
  if (n == "spindle_rpm_mode") return flag(!s.css);
  if (n == "spindle_css_mode") return flag(s.css);
  if (n == "ijk_absolute_mode") return flag(s.arc_absolute);
  if (n == "lathe_diameter_mode") return 0.0;
  if (n == "lathe_radius_mode") return 1.0;
  if (n == "speed_override" || n == "feed_override" || n == "feed_hold") return 1.0;
  if (n == "adaptive_feed") return 0.0;
  if (n == "u" || n == "v" || n == "w") return 0.0;
  return std::nullopt;
}

}  // namespace truecut::interp
