#include "truecut/interp/canon.hpp"

#include <cmath>
#include <type_traits>

namespace truecut::interp {

const char* call_name(const CanonOp& op) {
  return std::visit(
      [](const auto& c) -> const char* {
        using T = std::decay_t<decltype(c)>;
        if constexpr (std::is_same_v<T, StraightTraverse>) return "STRAIGHT_TRAVERSE";
        if constexpr (std::is_same_v<T, StraightFeed>) return "STRAIGHT_FEED";
        if constexpr (std::is_same_v<T, ArcFeed>) return "ARC_FEED";
        if constexpr (std::is_same_v<T, NurbsFeed>) return "NURBS_FEED";
        if constexpr (std::is_same_v<T, Dwell>) return "DWELL";
        if constexpr (std::is_same_v<T, SpeedFeedSync>)
          return c.on ? "START_SPEED_FEED_SYNC" : "STOP_SPEED_FEED_SYNCH";
        if constexpr (std::is_same_v<T, RigidTap>) return "RIGID_TAP";
        if constexpr (std::is_same_v<T, ProbeSwitch>)
          return c.on ? "TURN_PROBE_ON" : "TURN_PROBE_OFF";
        if constexpr (std::is_same_v<T, StraightProbe>) return "STRAIGHT_PROBE";
        if constexpr (std::is_same_v<T, SetFeedRate>) return "SET_FEED_RATE";
        if constexpr (std::is_same_v<T, SetFeedMode>) return "SET_FEED_MODE";
        if constexpr (std::is_same_v<T, SelectPlane>) return "SELECT_PLANE";
        if constexpr (std::is_same_v<T, UseLengthUnits>) return "USE_LENGTH_UNITS";
        if constexpr (std::is_same_v<T, SetMotionControlMode>) return "SET_MOTION_CONTROL_MODE";
        if constexpr (std::is_same_v<T, SetNaivecamTolerance>) return "SET_NAIVECAM_TOLERANCE";
        if constexpr (std::is_same_v<T, SetG5xOffset>) return "SET_G5X_OFFSET";
        if constexpr (std::is_same_v<T, SetG92Offset>) return "SET_G92_OFFSET";
        if constexpr (std::is_same_v<T, SetXYRotation>) return "SET_XY_ROTATION";
        if constexpr (std::is_same_v<T, UseToolLengthOffset>) return "USE_TOOL_LENGTH_OFFSET";
        if constexpr (std::is_same_v<T, SelectTool>) return "SELECT_TOOL";
        if constexpr (std::is_same_v<T, StartChange>) return "START_CHANGE";
        if constexpr (std::is_same_v<T, ChangeTool>) return "CHANGE_TOOL";
        if constexpr (std::is_same_v<T, ChangeToolNumber>) return "CHANGE_TOOL_NUMBER";
        if constexpr (std::is_same_v<T, SetToolTableEntry>) return "SET_TOOL_TABLE_ENTRY";
        if constexpr (std::is_same_v<T, SetSpindleSpeed>) return "SET_SPINDLE_SPEED";
        if constexpr (std::is_same_v<T, StartSpindle>)
          return c.clockwise ? "START_SPINDLE_CLOCKWISE" : "START_SPINDLE_COUNTERCLOCKWISE";
        if constexpr (std::is_same_v<T, StopSpindle>) return "STOP_SPINDLE_TURNING";
        if constexpr (std::is_same_v<T, OrientSpindle>) return "ORIENT_SPINDLE";
        if constexpr (std::is_same_v<T, WaitOrientComplete>)
          return "SPINDLE.0.WAIT_ORIENT_COMPLETE";
        if constexpr (std::is_same_v<T, OutputBit>) {
          if (c.synchronized) return c.on ? "SET_MOTION_OUTPUT_BIT" : "CLEAR_MOTION_OUTPUT_BIT";
          return c.on ? "SET_AUX_OUTPUT_BIT" : "CLEAR_AUX_OUTPUT_BIT";
        }
        if constexpr (std::is_same_v<T, OutputValue>)
          return c.synchronized ? "SET_MOTION_OUTPUT_VALUE" : "SET_AUX_OUTPUT_VALUE";
        if constexpr (std::is_same_v<T, AdaptiveFeed>)
          return c.enabled ? "ENABLE_ADAPTIVE_FEED" : "DISABLE_ADAPTIVE_FEED";
        if constexpr (std::is_same_v<T, FeedHold>)
          return c.enabled ? "ENABLE_FEED_HOLD" : "DISABLE_FEED_HOLD";
        if constexpr (std::is_same_v<T, FeedOverride>)
          return c.enabled ? "ENABLE_FEED_OVERRIDE" : "DISABLE_FEED_OVERRIDE";
        if constexpr (std::is_same_v<T, SpeedOverride>)
          return c.enabled ? "ENABLE_SPEED_OVERRIDE" : "DISABLE_SPEED_OVERRIDE";
        if constexpr (std::is_same_v<T, SetSpindleMode>) return "SET_SPINDLE_MODE";
        if constexpr (std::is_same_v<T, Coolant>) {
          if (c.kind == Coolant::kMist) return c.on ? "MIST_ON" : "MIST_OFF";
          return c.on ? "FLOOD_ON" : "FLOOD_OFF";
        }
        if constexpr (std::is_same_v<T, Comment>) return "COMMENT";
        if constexpr (std::is_same_v<T, Message>) return "MESSAGE";
        if constexpr (std::is_same_v<T, LogFile>) {
          switch (c.kind) {
            case LogFile::kOpen:
              return "LOGOPEN";
            case LogFile::kAppend:
              return "LOGAPPEND";
            case LogFile::kClose:
              return "LOGCLOSE";
            case LogFile::kLine:
              break;
          }
          return "LOG";
        }
        if constexpr (std::is_same_v<T, ProgramStop>)
          return c.optional ? "OPTIONAL_PROGRAM_STOP" : "PROGRAM_STOP";
        if constexpr (std::is_same_v<T, PalletShuttle>) return "PALLET_SHUTTLE";
        if constexpr (std::is_same_v<T, ProgramEnd>) return "PROGRAM_END";
        if constexpr (std::is_same_v<T, Finish>) return "FINISH";
        if constexpr (std::is_same_v<T, SetFeedReference>) return "SET_FEED_REFERENCE";
        if constexpr (std::is_same_v<T, OnReset>) return "ON_RESET";
        if constexpr (std::is_same_v<T, SetTcp>) return "SET_TCP";
        if constexpr (std::is_same_v<T, SetSplineMode>) return "SET_SPLINE_MODE";
      },
      op);
}

bool is_motion(const CanonOp& op) {
  return std::holds_alternative<StraightTraverse>(op) || std::holds_alternative<StraightFeed>(op) ||
         std::holds_alternative<ArcFeed>(op) || std::holds_alternative<NurbsFeed>(op);
}

Axes6 machine_position_mm(const Axes6& p, const CallContext& ctx) {
  const double scale = ctx.units == LengthUnits::kInch ? 25.4 : 1.0;
  Axes6 out;
  for (int i = 0; i < 6; ++i)
    out[i] = (i < 3 ? p[i] * scale : p[i]) + ctx.g5x_mm[i] + ctx.g92_mm[i] + ctx.tool_offset_mm[i];
  if (ctx.xy_rotation_deg != 0) {
    double x = p.x * scale + ctx.g92_mm.x, y = p.y * scale + ctx.g92_mm.y;
    rotate_xy_deg(x, y, ctx.xy_rotation_deg);
    out.x = x + ctx.g5x_mm.x + ctx.tool_offset_mm.x;
    out.y = y + ctx.g5x_mm.y + ctx.tool_offset_mm.y;
  }
  return out;
}

void rotate_xy_deg(double& x, double& y, double degrees) {
  const double t = degrees * (3.14159265358979323846 / 180.0);
  const double c = std::cos(t), s = std::sin(t);
  const double xx = x, yy = y;
  x = xx * c - yy * s;
  y = xx * s + yy * c;
}

}  // namespace truecut::interp
