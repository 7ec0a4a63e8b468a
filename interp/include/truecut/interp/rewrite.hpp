// The G-code rewriting fallback (`truecut rewrite`, docs/rewrite.md): for a
// controller that cannot take the real-time compensation module, the
// correction is written into the program. The moves of one CAM operation are
// densified, each point is shifted by the compensation at the tool there
// (compensation matrix, eqs. 2-5 of the optical-compensation source, or the
// real-time correction field) and written back as G1 moves; every other
// line is copied byte for byte.
//
//   RewriteOptions o;
//   o.operation = "SHAFT_PERIPHERAL"; o.type = CutType::kPeripheral;
//   o.interpreter.tools = ToolTable::load("tools.tbl");  // the radius: D / 2 of the tool
//   RewriteResult r = rewrite_program(text, "program.ngc", matrix, o);
//   // r.text: the new program; r.summary: counts and compensation figures
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "truecut/interp/interpreter.hpp"
#include "truecut/interp/rewrite_blend.hpp"
#include "truecut/interp/rewrite_matrix.hpp"
#include "truecut/rt/core/correction_field.hpp"
#include "truecut/rt/core/kinematics_ac.hpp"

namespace truecut::interp {

// Which part of the tool cuts, and so which compensation points belong to a
// tool point (docs/rewrite.md, "Nearest points considering the tool"):
// peripheral: the flat end mill's bottom cutting circle (radius R around
//   the axis at the tip); face: its bottom disc; ball: the ball (centre =
//   tip + R * axis).
enum class CutType { kPeripheral, kFace, kBall };

const char* to_string(CutType type);

// Matrix mode: which compensation points a tool point takes (docs/rewrite.md).
// kEveryPass: the source's blend at query points over the whole cutting part
//   (peripheral: the flank up to the cutting length; face: the bottom disc),
//   averaged, so every pass that sweeps a point takes its compensation, as
//   the field stage's tool-centre placement does. A ball cuts at its contact
//   point only: the same as kTip.
// kTip: the source's rule, the 3 nearest points to the cutting edge at the
//   tip (peripheral: the bottom circle).
enum class MatrixPlacement { kEveryPass, kTip };

const char* to_string(MatrixPlacement placement);

struct RewriteOptions {
  std::string operation;  // CAM operation name, as in (OPERATION: NAME)
  CutType type = CutType::kPeripheral;
  // The cutter radius of each move is that of the tool in the spindle (T..
  // M6), D / 2 in `interpreter.tools`, as everywhere else in truecut. When
  // set, the radius the caller believes: it must equal the table's for every
  // tool of the operation (RewriteError naming the tool and both values).
  std::optional<double> tool_radius_mm;
  double step_mm = 0.5;  // densification distance, > 0
  // G1 points the operation's feed moves may become in all, > 0 (a
  // GcodeError at the line that goes past it). The default, 2e7, is
  // 10 km of feed at 0.5 mm, about 800 MB of G-code.
  double max_points = 2e7;
  // Arcs: the most a written chord may leave the programmed arc (its sagitta),
  // > 0. Pieces of `step_mm` alone leave R (1 - cos(step / 2R)) inside the
  // arc: 19 um on a 1 mm tool-centre radius, the size of the compensation.
  double chord_tolerance_mm = 0.001;
  // Compensation points farther than this from the cutting part of the tool
  // are not used (infeed, retract and moves off the part stay unchanged).
  // 0: twice the median distance between neighbouring compensation points.
  double reach_mm = 0;
  MatrixPlacement placement = MatrixPlacement::kEveryPass;
  // kEveryPass, peripheral: how far up the flank cuts, from the tip.
  // 0: the tool length of the move (G43), or unlimited without one.
  double cutting_length_mm = 0;
  // Matrix mode: before the blend, every vector is replaced by the
  // Gaussian-weighted mean of the vectors of its surface within this radius
  // (sigma = radius / 2). 0: the matrix as it is.
  double smoothing_radius_mm = 0;
  // Use only the compensation points of these surfaces (empty: all).
  std::vector<std::int32_t> surfaces;
  // Machine kinematics for moves outside TRAORI (pivots; tool_length_mm is
  // added to the G43 tool length offset, as the planner does).
  rt::AcTrtParams kinematics;
  InterpreterOptions interpreter;  // tool table, block delete, ...
  // Digits after the point of X Y Z A C words, 3..9; 0: 4 in a G21 (mm)
  // block, 5 in a G20 (inch) block (0.1 um and 0.25 um).
  int decimals = 0;
  // A move whose every point keeps a zero correction is copied unchanged
  // (false: every feed move of the operation is densified and rewritten).
  bool keep_unchanged_moves = true;
};

struct RewriteSummary {
  int moves_read = 0;        // motion calls of the operation (G0 G1 G2 G3)
  int moves_rewritten = 0;   // feed moves written as densified G1
  int moves_kept = 0;        // motion lines of the operation copied unchanged
  int rapids_rewritten = 0;  // G0 after a compensated point, written with all of X Y Z
  // Another operation's first feed after a compensated point: a G1 back to
  // the original point written before its line, which is kept.
  int returns_written = 0;
  // Canned-cycle lines of the operation written with a corrected hole and
  // bottom (X Y Z), the cycle kept.
  int holes_rewritten = 0;
  // Loops, subroutine calls, NURBS blocks and lines replaced by the moves
  // they make (a feed of the operation ran more than once, in a subroutine
  // file, with parameters or expressions, in G91), and the moves written.
  int expansions = 0;
  long expanded_moves = 0;
  int expanded_holes = 0;       // canned-cycle holes of the operation among them
  long points_written = 0;      // G1 points written
  long points_compensated = 0;  // points with a correction from >= 1 point / field weight > 0
  // Points the compensation data covers, a correction or none: inside the
  // field's grid (its weight may be 0 there), or a matrix point within reach.
  long points_covered = 0;
  // Matrix mode: [1..3] blends (eqs. 2-5) by the number of points they used,
  // one per densified point with kTip, several per point with kEveryPass;
  // [0] densified points that no compensation point reached.
  std::array<long, 4> blend_points{};
  double max_compensation_mm = 0;
  double mean_compensation_mm = 0;  // over compensated points
  // Field mode with a rotation (issue 19): points whose A and C were turned
  // to lean the tool, the largest rotation asked for, and the largest part
  // of one A and C could not give (as truecut_comp in joint mode), rad.
  long points_rotated = 0;
  double max_rotation_rad = 0;
  double max_rotation_shortfall_rad = 0;
  double reach_mm = 0;  // the reach used
  // The tools of the operation's feed moves and their radii (tool table
  // D / 2), by tool number.
  std::vector<std::pair<int, double>> tool_radii_mm;
  int lines_in = 0, lines_out = 0;
};

struct RewriteResult {
  std::string text;
  RewriteSummary summary;
};

// Throws GcodeError (file:line:column) for a program error, a move that
// cannot be rewritten or a feed move of the operation without a tool in the
// spindle (or one the tool table does not hold), RewriteError for an
// unknown operation, a given tool radius that differs from the tool table's,
// an empty matrix selection or a field without the operation's tool, and
// std::invalid_argument for bad options. Before returning, the new text is
// interpreted again and checked: outside the rewritten lines it must give
// the same calls as the original, and the written points must come out as
// intended.
RewriteResult rewrite_program(std::string_view program_text, const std::string& program_name,
                              const CompensationMatrixData& matrix, const RewriteOptions& options);
// Field mode: the correction at each tool tip is the real-time evaluator's
// (CorrectionField::evaluate, layer of the operation's tool), as the
// compensation component would apply it.
RewriteResult rewrite_program(std::string_view program_text, const std::string& program_name,
                              const rt::CorrectionField& field, const RewriteOptions& options);

}  // namespace truecut::interp
