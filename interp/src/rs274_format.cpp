#include "truecut/interp/rs274_format.hpp"

#include <cstdio>
#include <type_traits>

#include "truecut/interp/path_geometry.hpp"

namespace truecut::interp {

namespace {

class Printer {
 public:
  explicit Printer(int decimals) : decimals_(decimals) {}
  std::string num(double v) const { return fixed(v, decimals_); }
  static std::string fixed(double v, int decimals) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
    return buf;
  }
  std::string axes(const Axes6& p) const {
    std::string s;
    for (int i = 0; i < 6; ++i)
      s += (i ? ", " : "") + num(p[i]);
    return s;
  }

 private:
  int decimals_;
};

const char* plane_text(Plane p) {
  switch (p) {
    case Plane::kXY:
      return "CANON_PLANE_XY";
    case Plane::kXZ:
      return "CANON_PLANE_XZ";
    case Plane::kYZ:
      return "CANON_PLANE_YZ";
  }
  return "";
}

const char* spline_text(SplineMode m) {
  switch (m) {
    case SplineMode::kNone:
      return "NONE";
    case SplineMode::kBspline:
      return "BSPLINE";
    case SplineMode::kCspline:
      return "CSPLINE";
  }
  return "";
}

}  // namespace

std::string format_rs274(const CanonOp& op, const FormatOptions& options) {
  const Printer p(options.decimals);
  const std::string name = call_name(op);
  return std::visit(
      [&](const auto& c) -> std::string {
        using T = std::decay_t<decltype(c)>;
        std::string args;
        if constexpr (std::is_same_v<T, StraightTraverse> || std::is_same_v<T, StraightFeed> ||
                      std::is_same_v<T, StraightProbe>) {
          args = p.axes(c.end);
        } else if constexpr (std::is_same_v<T, RigidTap>) {
          args = p.num(c.end.x) + ", " + p.num(c.end.y) + ", " + p.num(c.end.z);
        } else if constexpr (std::is_same_v<T, SpeedFeedSync>) {
          // rs274: "%f,0" (the pitch and "not CSS"); nothing when it stops.
          if (c.on) args = Printer::fixed(c.units_per_rev, options.decimals + 2) + ",0";
        } else if constexpr (std::is_same_v<T, ArcFeed>) {
          const path_geometry::PlaneAxes axes = path_geometry::plane_axes(c.plane);
          const int first = axes.first, second = axes.second, axis = axes.normal;
          args = p.num(c.end[first]) + ", " + p.num(c.end[second]) + ", " + p.num(c.center[first]) +
                 ", " + p.num(c.center[second]) + ", " + std::to_string(c.rotation) + ", " +
                 p.num(c.end[axis]) + ", " + p.num(c.end.a) + ", " + p.num(c.end.b) + ", " +
                 p.num(c.end.c);
        } else if constexpr (std::is_same_v<T, NurbsFeed>) {
          // rs274: the number of control points only.
          args = std::to_string(c.points.size()) + ", ...";
        } else if constexpr (std::is_same_v<T, Dwell>) {
          args = p.num(c.seconds);
        } else if constexpr (std::is_same_v<T, SetFeedRate>) {
          args = p.num(c.units_per_minute);
        } else if constexpr (std::is_same_v<T, SetFeedMode>) {
          // LinuxCNC's canonical feed mode stays units/minute under G93: the
          // interpreter turns each inverse-time F into a rate. G95: 1.
          args = c.mode == FeedMode::kUnitsPerRevolution ? "0, 1" : "0, 0";
        } else if constexpr (std::is_same_v<T, SelectPlane>) {
          args = plane_text(c.plane);
        } else if constexpr (std::is_same_v<T, UseLengthUnits>) {
          args = c.units == LengthUnits::kMm ? "CANON_UNITS_MM" : "CANON_UNITS_INCHES";
        } else if constexpr (std::is_same_v<T, SetMotionControlMode>) {
          if (c.mode == PathMode::kContinuous)
            args = "CANON_CONTINUOUS, " + Printer::fixed(c.tolerance, options.decimals + 2);
          else
            args = c.mode == PathMode::kExactPath ? "CANON_EXACT_PATH" : "CANON_EXACT_STOP";
        } else if constexpr (std::is_same_v<T, SetNaivecamTolerance>) {
          args = p.num(c.tolerance);
        } else if constexpr (std::is_same_v<T, SetG5xOffset>) {
          args = std::to_string(c.index) + ", " + p.axes(c.offset);
        } else if constexpr (std::is_same_v<T, SetG92Offset>) {
          args = p.axes(c.offset);
        } else if constexpr (std::is_same_v<T, SetXYRotation>) {
          args = p.num(c.degrees);
        } else if constexpr (std::is_same_v<T, UseToolLengthOffset>) {
          const Axes6& o = c.offset;
          args = p.num(o.x) + " " + p.num(o.y) + " " + p.num(o.z) + ", " + p.num(o.a) + " " +
                 p.num(o.b) + " " + p.num(o.c) + ", " + p.num(0) + " " + p.num(0) + " " + p.num(0);
        } else if constexpr (std::is_same_v<T, SelectTool>) {
          args = std::to_string(c.tool);
        } else if constexpr (std::is_same_v<T, ChangeTool> || std::is_same_v<T, ChangeToolNumber>) {
          args = std::to_string(c.slot);
        } else if constexpr (std::is_same_v<T, SetToolTableEntry>) {
          // rs274: pocket, tool, X Y Z A B C U V W, front and back angle,
          // orientation (the diameter is not printed).
          const Axes6& o = c.offset;
          args = std::to_string(c.pocket) + ", " + std::to_string(c.tool) + ", " + p.num(o.x) +
                 " " + p.num(o.y) + " " + p.num(o.z) + " " + p.num(o.a) + " " + p.num(o.b) + " " +
                 p.num(o.c) + " " + p.num(0) + " " + p.num(0) + " " + p.num(0) + ", " +
                 p.num(c.front_angle_deg) + ", " + p.num(c.back_angle_deg) + ", " +
                 std::to_string(c.orientation);
        } else if constexpr (std::is_same_v<T, SetSpindleSpeed>) {
          args = "0, " + p.num(c.rpm);
        } else if constexpr (std::is_same_v<T, StartSpindle> || std::is_same_v<T, StopSpindle>) {
          args = "0";
        } else if constexpr (std::is_same_v<T, SpeedOverride>) {
          args = "0";
        } else if constexpr (std::is_same_v<T, OrientSpindle>) {
          // LinuxCNC's CANON_DIRECTION: 2 clockwise, 3 counter-clockwise.
          args = "0, " + p.num(c.degrees) + ", " +
                 (c.m19_direction >= 0 ? std::to_string(c.m19_direction)
                                       : std::string(c.clockwise ? "2" : "3"));
        } else if constexpr (std::is_same_v<T, WaitOrientComplete>) {
          args = p.num(c.timeout_s);
        } else if constexpr (std::is_same_v<T, OutputBit>) {
          args = std::to_string(c.index);
        } else if constexpr (std::is_same_v<T, OutputValue>) {
          // rs274: "%d,%f" (no space, six decimals).
          args = std::to_string(c.index) + "," + Printer::fixed(c.value, options.decimals + 2);
        } else if constexpr (std::is_same_v<T, SetSpindleMode>) {
          args = "0 " + p.num(c.css_max_rpm);
        } else if constexpr (std::is_same_v<T, Comment> || std::is_same_v<T, Message>) {
          args = "\"" + c.text + "\"";
        } else if constexpr (std::is_same_v<T, LogFile>) {
          if (c.kind != LogFile::kClose) args = "\"" + c.text + "\"";
        } else if constexpr (std::is_same_v<T, SetFeedReference>) {
          args = "CANON_XYZ";
        } else if constexpr (std::is_same_v<T, SetTcp>) {
          args = c.on ? "ON" : "OFF";
        } else if constexpr (std::is_same_v<T, SetSplineMode>) {
          args = spline_text(c.mode);
        }
        return name + "(" + args + ")";
      },
      op);
}

}  // namespace truecut::interp
