// The interpreter's modal state between blocks. Positions and offsets are
// kept in machine units (mm, degrees); canonical calls are in program units.
#pragma once

#include <string>
#include <vector>

#include "truecut/interp/canon.hpp"

namespace truecut::interp {

constexpr double kMmPerInch = 25.4;
// G96 without D: rs274's "no limit" (printed as 1e30).
constexpr double kNoCssLimit = 1e30;

// The canned cycles' memory between blocks (G73, G81-G83, G85, G86, G88, G89).
struct CycleState {
  int last_code = -1;      // the cycle of the last cycle block, -1 after any other motion
  bool level_set = false;  // `level` holds the initial level of this run of cycles
  double level = 0;        // program units, along the axis normal to the plane
  double r = 0, bottom = 0, p = 0, q = 0;  // sticky R, Z (X, Y), P, Q words as written
  double ijk[3] = {0, 0, 0};               // G87's sticky I J K words as written
  int running = 0;  // the cycle whose moves are being made (its code x10), else 0
};

// Cutter radius compensation (G40/G41/G42/G41.1/G42.1) between blocks, in
// program units and the two coordinates of the plane (cutter_comp.cpp).
struct CutterCompState {
  int side = 0;                  // 1 left (G41), -1 right (G42), 0 off (G40)
  double radius = 0;             // program units; 0 = on but moves pass unchanged
  bool first_move = true;        // the next move is the entry move
  bool arc_not_allowed = false;  // the move after a G40 exit must be straight
  Axes6 programmed;              // the uncompensated end of the last move (program units)
  double endpoint[2] = {0, 0};   // start of the held moves, for the gouge checks
  bool endpoint_valid = false;
  bool active() const { return side != 0 && radius > 0; }
};

// A G5.2 NURBS being collected until its G5.3 (splines.cpp).
struct NurbsRun {
  std::vector<NurbsControlPoint> points;  // program units; points[0]: where it starts
  int order = 3;
  int line = 0;  // the line of its first G5.2 block
};

// rs274's motion mode after G5.3: none (axis words alone are an error).
constexpr int kMotionNone = -1;

struct InterpState {
  // Active motion code x10 (G80: none), a spline code, or kMotionNone.
  int motion = 800;
  Plane plane = Plane::kXY;
  LengthUnits units = LengthUnits::kMm;
  bool incremental = false;   // G91
  bool arc_absolute = false;  // G90.1
  FeedMode feed_mode = FeedMode::kUnitsPerMinute;
  PathMode path = PathMode::kContinuous;
  double blend_tolerance = 0;  // the last G64 P
  double naive_tolerance = 0;  // the last G64 Q
  double feed = 0;             // program units per minute (G94)
  double speed = 0;            // rpm (m/min, ft/min in G20 under G96)
  bool css = false;            // G96 constant surface speed (else G97)
  double css_max_rpm = 0;      // G96's D (1e30 without D)
  int spindle = 0;             // 1 cw, -1 ccw, 0 stopped
  bool mist = false, flood = false;
  bool feed_override = true;  // M48/M49/M50 (M2 switches it back on)
  int tool = 0;               // in the spindle
  int selected_tool = 0;      // by the last T word
  // The tool table row (1-based) rs274 takes as the spindle's for G10 L1's
  // spindle copy: M6/M61 set it (0 for T0); standalone rs274 starts at 1.
  int spindle_slot = 1;
  int coord_index = 1;         // 1 = G54 ... 9 = G59.3
  int tool_length_code = 490;  // G43 (430) or G49 (490) in force
  Axes6 g5x_mm, g92_mm, tool_offset_mm;
  double rotation_deg = 0;     // XY rotation of the active system (G10 L2 R, #5230 ...)
  Axes6 position_mm;           // controlled point in machine coordinates
  bool retract_old_z = false;  // G98 (else G99)
  CycleState cycle;
  CutterCompState comp;
  NurbsRun nurbs;
  int line = 0;  // source line being executed
  bool tcp = false;
  SplineMode spline = SplineMode::kNone;
  std::string operation;

  double scale() const { return units == LengthUnits::kInch ? kMmPerInch : 1.0; }
  // The offset parameters (#5161.., #5211.., #5221..) hold lengths in the
  // machine's units, whatever G20/G21 is in force, as in rs274 (the
  // parameter file's units: its INI's LINEAR_UNITS).
  LengthUnits machine_units = LengthUnits::kMm;
  double from_param(int axis, double value) const {
    return axis < 3 && machine_units == LengthUnits::kInch ? value * kMmPerInch : value;
  }
  double to_param(int axis, double mm) const {
    return axis < 3 && machine_units == LengthUnits::kInch ? mm / kMmPerInch : mm;
  }
  // Program-unit value of machine-unit length `mm` on axis i (0..5).
  double to_program(int axis, double mm) const { return axis < 3 ? mm / scale() : mm; }
  double to_machine(int axis, double value) const { return axis < 3 ? value * scale() : value; }
  Axes6 to_program(const Axes6& mm) const;
  // Position `machine` expressed in the work coordinate system:
  // program XY = rotation^-1 x (machine - G5x - tool) - G92.
  Axes6 program_position(const Axes6& machine) const;
  // Machine position of program position `program` (the inverse).
  Axes6 machine_position(const Axes6& program) const;
  Axes6 program_position() const { return program_position(position_mm); }
};

}  // namespace truecut::interp
