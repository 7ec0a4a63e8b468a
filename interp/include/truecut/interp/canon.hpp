// The canonical machining calls the interpreter emits: one call per motion
// or state change, in program order, in the spirit of RS274/NGC's canonical
// machining functions (and of what LinuxCNC's `rs274` prints). The
// interpreter knows nothing about time: a later stage plans the motion.
//
// Positions are in the active work coordinate system (G5x + G92 + tool length
// offset already subtracted), in the active program units (mm or inch) for
// X Y Z and degrees for A B C, exactly as rs274 reports them. Each call
// carries the offsets and units in force (CallContext) so that a consumer can
// recover machine positions in mm with machine_position_mm().
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <variant>
#include <vector>

namespace truecut::interp {

struct Axes6 {
  double x = 0, y = 0, z = 0, a = 0, b = 0, c = 0;
  double& operator[](int i) { return (&x)[i]; }
  double operator[](int i) const { return (&x)[i]; }
  friend bool operator==(const Axes6&, const Axes6&) = default;
};

enum class Plane { kXY, kYZ, kXZ };  // G17, G19, G18
enum class LengthUnits { kMm, kInch };
// G94, G93, G95 (F in program units per spindle revolution).
enum class FeedMode { kUnitsPerMinute, kInverseTime, kUnitsPerRevolution };
enum class PathMode { kExactStop, kExactPath, kContinuous };  // G61.1, G61, G64
// Sinumerik spline interpolation, in the motion group with G0..G3.
enum class SplineMode { kNone, kBspline, kCspline };

// Straight moves and arcs.
struct StraightTraverse {  // G0
  Axes6 end;
};
struct StraightFeed {  // G1 (and spline-mode points, see CallContext::spline)
  Axes6 end;
};
// G2/G3, helical when the axis coordinate changes. `center` holds the centre
// in the two plane coordinates (the third is unused). rotation < 0 is
// clockwise; |rotation| is the number of turns (1 for an arc under a turn).
struct ArcFeed {
  Axes6 end;
  Axes6 center;
  Plane plane = Plane::kXY;
  int rotation = 1;
};
// G5 (cubic), G5.1 (quadratic) and G5.2 ... G5.3 (NURBS): a rational
// B-spline in X and Y as LinuxCNC hands it to NURBS_FEED. `points` are the
// control points in program units (the first is where the tool was) with
// their weights; `order` k is 4 for G5, 3 for G5.1, L (at least 3) for G5.2.
// The knots are LinuxCNC's: k times 0, then 1 ... n-k+1, then k times
// n-k+2 for n+1 points (nurbs.hpp evaluates the curve). Z A B C do not
// move; `end` is the position afterwards (X Y of the last control point).
// rs274 prints NURBS_FEED(number of points, ...).
struct NurbsControlPoint {
  double x = 0, y = 0, weight = 1;
};
struct NurbsFeed {
  std::vector<NurbsControlPoint> points;
  int order = 3;
  Axes6 end;
};
struct Dwell {
  double seconds = 0;
};
// G33/G33.1: the moves between on and off advance `units_per_rev` (K, program
// units) per spindle revolution instead of at F.
struct SpeedFeedSync {
  bool on = false;
  double units_per_rev = 0;
};
// G33.1: feed to `end` synchronised with the spindle, reverse it and come
// back to where the tap started (the position does not change). rs274
// prints X Y Z only; A B C stay where they are.
struct RigidTap {
  Axes6 end;
};
// G38.2-G38.5 between TURN_PROBE_ON and TURN_PROBE_OFF: a straight feed to
// `end` that stops where the probe trips (2, 4: toward the work, error if it
// does not; 3, 5: no error) or loses contact (4, 5).
struct ProbeSwitch {
  bool on = false;
};
struct StraightProbe {
  Axes6 end;     // as programmed (rs274 prints it)
  int kind = 2;  // G38.kind
  // What the probe reported (InterpreterOptions::probe): where it tripped
  // (`end` when it did not) and where the machine stopped; the next move
  // starts there.
  Axes6 trip, stopped;
};

// Feed and motion settings.
// Feed in program units per minute, or per spindle revolution under G95
// (CallContext::feed_mode). In inverse-time mode (G93) the
// interpreter converts each move's F into the equivalent rate, like LinuxCNC;
// CallContext::inverse_time_f keeps the programmed value.
struct SetFeedRate {
  double units_per_minute = 0;
};
struct SetFeedMode {
  FeedMode mode = FeedMode::kUnitsPerMinute;
};
struct SelectPlane {
  Plane plane = Plane::kXY;
};
struct UseLengthUnits {
  LengthUnits units = LengthUnits::kMm;
};
struct SetMotionControlMode {
  PathMode mode = PathMode::kContinuous;
  double tolerance = 0;  // G64 P, program units; 0 = as fast as possible
};
struct SetNaivecamTolerance {
  double tolerance = 0;  // G64 Q
};

// Offsets (program units, degrees for rotary axes).
struct SetG5xOffset {
  int index = 1;  // 1 = G54 ... 9 = G59.3
  Axes6 offset;
};
struct SetG92Offset {
  Axes6 offset;
};
struct SetXYRotation {
  double degrees = 0;
};
struct UseToolLengthOffset {
  Axes6 offset;
};

// Tools and spindle.
struct SelectTool {  // T word
  int tool = 0;
};
struct StartChange {};
struct ChangeTool {  // M6
  int tool = 0;
  int slot = 0;  // 1-based row of the tool in the tool table (rs274's number)
};
struct ChangeToolNumber {  // M61 Q
  int tool = 0;
  int slot = 0;  // 1-based row of the tool in the tool table (rs274 prints it)
};
// G10 L1/L10/L11: a tool table entry changed. `pocket` is the tool's row
// in the table (1-based, rs274's number; 0: the tool in the spindle, sent
// after the row when the edited tool is in the spindle). Offsets and the
// diameter in program units (degrees for A B C).
struct SetToolTableEntry {
  int pocket = 0;
  int tool = 0;
  Axes6 offset;
  double diameter = 0;
  double front_angle_deg = 0, back_angle_deg = 0;
  int orientation = 0;
};
struct SetSpindleSpeed {
  double rpm = 0;
};
struct StartSpindle {
  bool clockwise = true;
};
struct StopSpindle {};
// Stops the spindle at an angle (G87 before it enters and leaves the hole,
// M19); `clockwise`: the direction it turned in, as rs274 passes it on for
// G87. M19 passes its P (0 either way, 1 clockwise, 2 counter-clockwise) as
// `m19_direction` instead.
struct OrientSpindle {
  double degrees = 0;
  bool clockwise = true;
  int m19_direction = -1;  // >= 0: M19's P
};
// M19 Q: wait up to `timeout_s` for the orientation (rs274 prints
// SPINDLE.0.WAIT_ORIENT_COMPLETE).
struct WaitOrientComplete {
  double timeout_s = 0;
};
// M62-M65: a digital output, with the next motion (`synchronized`: M62 M63)
// or at once (M64 M65).
struct OutputBit {
  int index = 0;
  bool on = false;
  bool synchronized = false;
};
// M67 (with the next motion) and M68 (at once): an analog output.
struct OutputValue {
  int index = 0;
  double value = 0;
  bool synchronized = false;
};
// M52 (adaptive feed) and M53 (feed hold switch) P1 / P0.
struct AdaptiveFeed {
  bool enabled = true;
};
struct FeedHold {
  bool enabled = true;
};
// The feed and spindle speed overrides switched off and on again around the
// tapping cycles G74/G84, as LinuxCNC does.
struct FeedOverride {
  bool enabled = true;
};
struct SpeedOverride {
  bool enabled = true;
};
// G96 (constant surface speed: the S words that follow are m/min, ft/min
// in G20, up to `css_max_rpm`, D; 1e30 without D, as rs274) or G97 (0).
struct SetSpindleMode {
  double css_max_rpm = 0;
  bool constant_surface_speed = false;  // G96 (rs274 prints css_max_rpm only)
};
struct Coolant {
  enum Kind { kMist, kFlood } kind = kFlood;
  bool on = false;
};

// Program flow and text.
struct Comment {
  std::string text;
  // G10 L2/L20 of a system not in use makes only rs274's comment "interpreter:
  // setting coordinate system origin"; truecut also carries the system and
  // the origin it now has (program units, as SET_G5X_OFFSET, and its
  // rotation), which the canon text does not print.
  int sets_system = 0;  // 1..9 (G54..G59.3), 0: none
  Axes6 system_origin{};
  double system_rotation_deg = 0;
};
struct Message {  // (MSG, ...)
  std::string text;
};
// (LOGOPEN,file) (LOGAPPEND,file) (LOGCLOSE) (LOG,text): LinuxCNC's log
// file, as canonical calls (truecut writes no file; a consumer may).
struct LogFile {
  enum Kind { kOpen, kAppend, kClose, kLine } kind = kLine;
  std::string text;  // file name, or the line with #n/#<name> replaced
};
struct ProgramStop {  // M0, or M1 when optional
  bool optional = false;
};
struct PalletShuttle {};  // M30 (printed by rs274 before PROGRAM_END)
struct ProgramEnd {};
struct Finish {};  // the program stopped at its closing '%' line, without M2/M30
// Bookkeeping calls rs274 prints at start and end of a program.
struct SetFeedReference {};
struct OnReset {};

// Sinumerik modes (truecut extensions, not printed by rs274).
struct SetTcp {  // TRAORI (on) / TRAFOOF (off)
  bool on = false;
};
struct SetSplineMode {  // BSPLINE, CSPLINE, or back to G1
  SplineMode mode = SplineMode::kNone;
};

using CanonOp =
    std::variant<StraightTraverse, StraightFeed, ArcFeed, NurbsFeed, Dwell, SpeedFeedSync, RigidTap,
                 ProbeSwitch, StraightProbe, SetFeedRate, SetFeedMode, SelectPlane, UseLengthUnits,
                 SetMotionControlMode, SetNaivecamTolerance, SetG5xOffset, SetG92Offset,
                 SetXYRotation, UseToolLengthOffset, SelectTool, StartChange, ChangeTool,
                 ChangeToolNumber, SetToolTableEntry, SetSpindleSpeed, StartSpindle, StopSpindle,
                 OrientSpindle, WaitOrientComplete, OutputBit, OutputValue, AdaptiveFeed, FeedHold,
                 FeedOverride, SpeedOverride, SetSpindleMode, Coolant, Comment, Message, LogFile,
                 ProgramStop, PalletShuttle, ProgramEnd, Finish, SetFeedReference, OnReset, SetTcp,
                 SetSplineMode>;

// What was in force when a call was made.
struct CallContext {
  int file = 0;  // index into CanonProgram::files
  int line = 0;  // 1-based line in that file
  // The digits of the block's N word as written ("00010"), "" without one;
  // rs274 prints them in its second column.
  std::string block_number;
  // The block's place in the run: counts the blocks executed, so a line run
  // again (in a loop or subroutine) gets a new number each time.
  long executed_block = 0;
  // Where the main program stands when the call is made: the line being run
  // there (the calling line while a subroutine runs), and the first line of
  // the outermost loop running there (0: none). The rewrite expands such a
  // line or loop when moves inside it cannot be corrected in place.
  int outer_line = 0;
  int outer_loop_line = 0;
  std::string operation;  // CAM operation name, "" before the first marker
  int tool = 0;           // tool in the spindle
  LengthUnits units = LengthUnits::kMm;
  FeedMode feed_mode = FeedMode::kUnitsPerMinute;
  bool incremental = false;   // G91 in force
  double inverse_time_f = 0;  // the programmed F of an inverse-time move
  SplineMode spline = SplineMode::kNone;
  bool tcp = false;  // TRAORI active
  // Under cutter radius compensation (G41/G42 with a radius > 0): the
  // move's positions are those of the compensated tool, not as programmed.
  bool cutter_comp = false;
  // A move of a canned cycle: its G code x10 (810 for G81), else 0; with the
  // plane and distance mode the cycle ran in. The rewrite corrects a
  // cycle's hole on the cycle's own line (docs/rewrite.md).
  int canned_cycle = 0;
  Plane cycle_plane = Plane::kXY;
  bool cycle_incremental = false;
  // Offsets in mm (degrees for A B C) that turn positions into machine ones.
  Axes6 g5x_mm, g92_mm, tool_offset_mm;
  // XY rotation of the active coordinate system (G10 L2 R), degrees
  // counter-clockwise: machine XY = G5x + rotation x (program + G92) + tool.
  double xy_rotation_deg = 0;
};

struct CanonCall {
  CallContext context;
  CanonOp op;
};

struct CanonProgram {
  std::vector<std::string> files;  // main program first, then subroutine files
  std::vector<CanonCall> calls;
  // Loops of the main program that no loop there encloses, by their first
  // line: the line they ended at (their endwhile or endrepeat, the while of
  // a do, or the end a break left them for); 0 when runs of one ended at
  // different lines. The rewrite finds the end of a loop whose label is
  // computed (o[#1] while) here.
  std::map<int, int> loop_last_lines;
};

// Receives canonical calls one by one (InterpreterOptions::on_call).
using CanonSink = std::function<void(const CanonCall& call, const std::vector<std::string>& files)>;

// Name of the call as rs274 prints it (e.g. "STRAIGHT_FEED").
const char* call_name(const CanonOp& op);
bool is_motion(const CanonOp& op);  // traverse, feed, arc or NURBS

// Machine position (mm, degrees) of a programmed position under `ctx`:
// X Y Z as program + G92, turned by the XY rotation, + G5x + tool offset.
Axes6 machine_position_mm(const Axes6& program_position, const CallContext& ctx);
// Turns (x, y) counter-clockwise by `degrees` about the origin.
void rotate_xy_deg(double& x, double& y, double degrees);

}  // namespace truecut::interp
