// rewrite_program: the source's G-code adaptation (docs/rewrite.md).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>

#include "expansion.hpp"
#include "line_words.hpp"
#include "modal_groups.hpp"
#include "neighbours.hpp"
#include "raw_lines.hpp"
#include "self_check.hpp"
#include "smoothing.hpp"
#include "swept.hpp"
#include "tool_path.hpp"
#include "truecut/interp/error.hpp"
#include "truecut/interp/nurbs.hpp"
#include "truecut/interp/operations.hpp"
#include "truecut/interp/path_geometry.hpp"
#include "truecut/interp/rewrite.hpp"
#include "truecut/rt/number_format.hpp"

namespace truecut::interp {

const char* to_string(CutType type) {
  switch (type) {
    case CutType::kPeripheral:
      return "peripheral";
    case CutType::kFace:
      return "face";
    case CutType::kBall:
      return "ball";
  }
  return "?";
}

const char* to_string(MatrixPlacement placement) {
  return placement == MatrixPlacement::kTip ? "tip" : "every-pass";
}

namespace rewrite {
namespace {

struct Correction {
  Eigen::Vector3d shift_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d rotation_rad = Eigen::Vector3d::Zero();  // field mode: the tool's lean
  bool compensated = false;
  // Inside what the compensation data covers (field: its grid; matrix: a
  // point within reach), whether or not it holds a correction there.
  bool covered = false;
  std::array<int, 4> blends{};  // matrix mode: blends by points used; [0] none at all
};

// The correction at a tool point of a move whose cutter has radius `radius_mm`.
using CorrectionFn =
    std::function<Correction(const ToolPoint&, const CallContext&, double radius_mm)>;
// Called once the radii of the operation's tools are known (distinct values,
// ascending; empty when the operation has no feed move): prepares the
// corrections and returns the reach used (0: none).
using PrepareFn = std::function<double(const std::vector<double>& radii_mm)>;

// The shortest decimal that reads back to the same double (written ends of
// rapids reproduce the original position exactly).
std::string exact(double v) {
  // Fixed notation (G-code has no exponents), the fewest decimals that
  // read back to v: "30", not "3e+01"; 12 decimals when none does.
  char buf[400];
  int decimals = 0;
  for (; decimals <= 17; ++decimals) {
    std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  if (decimals > 17) std::snprintf(buf, sizeof buf, "%.12f", v);
  std::string s = buf;
  if (s == "-0") s = "0";
  return s;
}

// " X.. Y.. Z.." (and A, C when asked) in exact() decimals; `read` gets
// the values the interpreter will read back from them.
std::string exact_words(const Axes6& p, bool with_a, bool with_c, Axes6& read) {
  std::string words;
  const char letters[] = {'X', 'Y', 'Z', 'A', 'B', 'C'};
  for (int ax : {0, 1, 2, 3, 5}) {
    if ((ax == 3 && !with_a) || (ax == 5 && !with_c)) continue;
    const std::string v = exact(p[ax]);
    words += std::string(" ") + letters[ax] + v;
    read[ax] = std::strtod(v.c_str(), nullptr);
  }
  return words;
}

// A feed with up to 4 decimals and no trailing zeros ("F500", "F1234.5").
std::string feed_text(double v) {
  std::string s = rt::format_fixed(v, 4);
  if (s.find('.') != std::string::npos) {
    while (s.back() == '0')
      s.pop_back();
    if (s.back() == '.') s.pop_back();
  }
  return s;
}

int motion_mode(const CanonOp& op) {  // 0 G0, 1 G1, 2 G2, 3 G3
  if (std::holds_alternative<StraightTraverse>(op)) return 0;
  if (const auto* a = std::get_if<ArcFeed>(&op)) return a->rotation < 0 ? 2 : 3;
  return 1;
}

void check_options(const RewriteOptions& o) {
  if (o.operation.empty()) throw std::invalid_argument("no operation name given");
  if (!(o.step_mm > 0) || !std::isfinite(o.step_mm))
    throw std::invalid_argument("step must be > 0 mm (got " + std::to_string(o.step_mm) + ")");
  if (o.tool_radius_mm && (!(*o.tool_radius_mm >= 0) || !std::isfinite(*o.tool_radius_mm)))
    throw std::invalid_argument("tool radius must be >= 0 mm");
  if (!(o.max_points > 0)) throw std::invalid_argument("the limit of G1 points must be > 0");
  if (!(o.chord_tolerance_mm > 0) || !std::isfinite(o.chord_tolerance_mm))
    throw std::invalid_argument("chord tolerance must be > 0 mm");
  if (!(o.reach_mm >= 0) || !std::isfinite(o.reach_mm))
    throw std::invalid_argument("reach must be >= 0 mm (0: automatic)");
  if (!(o.smoothing_radius_mm >= 0) || !std::isfinite(o.smoothing_radius_mm))
    throw std::invalid_argument("smoothing radius must be >= 0 mm");
  if (!(o.cutting_length_mm >= 0) || !std::isfinite(o.cutting_length_mm))
    throw std::invalid_argument("cutting length must be >= 0 mm (0: the tool length)");
  if (o.decimals != 0 && (o.decimals < 3 || o.decimals > 9))
    throw std::invalid_argument("decimals must be 3..9 (0: automatic)");
}

// Pieces so that neither the point the compensation is looked up for (tip,
// or ball centre) nor the cutting edge turning about it (R per radian of
// the tool axis) moves more than one step per piece.
// Returned as a real number: a move beyond any machine's travel asks for
// more pieces than an int holds (the caller refuses such a move).
double pieces_for_step(const ToolPath& path, const ToolPath::Move& m, const CallContext& ctx,
                       const RewriteOptions& o, double radius_mm) {
  constexpr int kSamples = 64;
  double length_mm = 0, turn_rad = 0;
  ToolPoint prev = path.tool_point(m.start, ctx);
  auto ref = [&](const ToolPoint& t) -> Eigen::Vector3d {
    return o.type == CutType::kBall ? Eigen::Vector3d(t.tip_mm + radius_mm * t.axis) : t.tip_mm;
  };
  for (int k = 1; k <= kSamples; ++k) {
    const ToolPoint t = path.tool_point(ToolPath::at(m, static_cast<double>(k) / kSamples), ctx);
    length_mm += (ref(t) - ref(prev)).norm();
    turn_rad += std::acos(std::clamp(t.axis.dot(prev.axis), -1.0, 1.0));
    prev = t;
  }
  const double longest = std::max(length_mm, radius_mm * turn_rad);
  return std::max(1.0, std::ceil(longest / o.step_mm - 1e-9));
}

// More G1 points than this for one program line (its move, or all the
// chords of a G5 line together; 500 m at the default 0.5 mm step) is
// refused: no part's move is that long.
constexpr double kMaxPiecesPerMove = 1e6;

// Pieces of an arc so that no chord's sagitta r (1 - cos(sweep / 2n))
// exceeds the tolerance (r: the larger of the start and end radii).
int pieces_for_chord(const ToolPath::Move& m, const RewriteOptions& o) {
  if (!m.arc) return 1;
  return path_geometry::arc_pieces_for_chord(
      std::max(m.plane.start_radius_mm, m.plane.end_radius_mm), m.plane.sweep_rad,
      o.chord_tolerance_mm);
}

struct PlannedLine {               // what replaces one program line
  std::string residual;            // the line without its move, "" for none
  std::vector<std::string> moves;  // G1 lines, without terminators
  bool last_verbatim = false;      // the last of `moves` is the source line itself
};

Axes6 end_of(const CanonOp& op) {
  if (const auto* a = std::get_if<ArcFeed>(&op)) return a->end;
  if (const auto* f = std::get_if<StraightFeed>(&op)) return f->end;
  if (const auto* n = std::get_if<NurbsFeed>(&op)) return n->end;
  return std::get<StraightTraverse>(op).end;
}

std::string file_of(const CanonProgram& program, const CallContext& ctx, const std::string& name) {
  return ctx.file < static_cast<int>(program.files.size()) ? program.files[ctx.file] : name;
}

// G5, G5.1 and NURBS blocks of the operation (docs/rewrite.md): each
// NURBS_FEED becomes the G1 chords of its curve within the chord
// tolerance, which the rewrite then corrects like any feed; returns the
// lines of the G5 and G5.1 (corrected in place) and gives the NURBS blocks
// (written out in place of their lines). Splines outside it are copied.
std::set<int> expand_splines(CanonProgram& program, const std::vector<RawLine>& raw,
                             const std::string& name, const RewriteOptions& o,
                             std::vector<NurbsBlock>& nurbs_blocks) {
  std::set<int> lines;
  std::vector<CanonCall> calls;
  calls.reserve(program.calls.size());
  for (CanonCall& c : program.calls) {
    const auto* n = std::get_if<NurbsFeed>(&c.op);
    if (!n || c.context.operation != o.operation) {
      calls.push_back(std::move(c));
      continue;
    }
    const SourceLocation at{file_of(program, c.context, name), c.context.line, 0};
    // A spline of a subroutine file is written out with the calling line
    // (expansion.hpp); a NURBS block (G5.2 ... G5.3) spans several lines and
    // is written out in their place.
    bool block = false;
    if (c.context.file == 0) {
      const std::string& source = raw.at(static_cast<std::size_t>(c.context.line) - 1).content;
      if (line_has_g_code(source, 52) || line_has_g_code(source, 53)) {
        int first = c.context.line;
        while (first > 1 && !line_has_g_code(raw[static_cast<std::size_t>(first) - 1].content, 52))
          --first;
        if (!line_has_g_code(raw[static_cast<std::size_t>(first) - 1].content, 52))
          throw GcodeError(at, "NURBS block of the operation without its G5.2 line");
        nurbs_blocks.push_back({first, c.context.line, c.context.outer_line});
        block = true;
      }
    }
    const double units_mm = c.context.units == LengthUnits::kInch ? 25.4 : 1.0;
    // Its G1 points number at least its length over the step: refused before
    // a million of them are corrected only to be refused later. The length
    // of a polygon through points of the curve is at most the curve's.
    auto refuse_longer = [&](NurbsPoint2 from, const std::vector<NurbsPoint2>& curve_points) {
      double length_mm = 0;
      for (const NurbsPoint2& q : curve_points) {
        length_mm += std::hypot(q[0] - from[0], q[1] - from[1]) * units_mm;
        from = q;
      }
      if (!(length_mm / o.step_mm <= kMaxPiecesPerMove))
        throw GcodeError(at,
                         rt::format_printf("spline would be written as at least %.3g G1 points "
                                           "of at most %g mm (more than %.0f): it is longer "
                                           "than any part's move",
                                           length_mm / o.step_mm, o.step_mm, kMaxPiecesPerMove));
    };
    // First from a few points (a curve thousands of km long would otherwise
    // be cut into millions of chords first), then from the chords.
    constexpr int kSamplesPerSpan = 8;
    const int samples = kSamplesPerSpan * static_cast<int>(std::lround(nurbs_parameter_end(*n)));
    const NurbsPoint2 start{n->points.front().x, n->points.front().y};
    std::vector<NurbsPoint2> coarse;
    for (int i = 1; i <= samples; ++i)
      coarse.push_back(nurbs_point(*n, static_cast<double>(i) / kSamplesPerSpan));
    refuse_longer(start, coarse);
    const std::vector<NurbsPoint2> chord_ends = nurbs_polyline(*n, o.chord_tolerance_mm / units_mm);
    refuse_longer(start, chord_ends);
    for (const NurbsPoint2& q : chord_ends) {
      StraightFeed f;
      f.end = n->end;
      f.end[0] = q[0];
      f.end[1] = q[1];
      calls.push_back({c.context, f});
    }
    // The last chord ends exactly at the spline's end.
    std::get<StraightFeed>(calls.back().op).end = n->end;
    if (c.context.file == 0 && !block) lines.insert(c.context.line);
  }
  program.calls = std::move(calls);
  return lines;
}

// The cutter radius of every tool that makes a feed move of the operation:
// D / 2 from the tool table, as everywhere else in truecut.
std::map<int, double> tool_radii(const CanonProgram& program, const std::string& name,
                                 const RewriteOptions& o) {
  std::map<int, double> radii;
  for (const CanonCall& c : program.calls) {
    const CallContext& ctx = c.context;
    if (ctx.operation != o.operation || !is_motion(c.op) ||
        std::holds_alternative<StraightTraverse>(c.op) || radii.count(ctx.tool))
      continue;
    const SourceLocation at{file_of(program, ctx, name), ctx.line, 0};
    if (ctx.tool == 0)
      throw GcodeError(at, "feed move of operation '" + o.operation +
                               "' with no tool in the spindle: the tool radius comes from the "
                               "tool table (select the tool with T.. M6 before the move)");
    const ToolEntry* entry = o.interpreter.tools.find(ctx.tool);
    if (!entry)
      throw GcodeError(at, "tool T" + std::to_string(ctx.tool) + " of operation '" + o.operation +
                               "' is not in the tool table: its radius (D / 2) comes from there");
    const double radius = entry->diameter_mm / 2;
    if (!(radius >= 0) || !std::isfinite(radius))
      throw GcodeError(at, "tool T" + std::to_string(ctx.tool) +
                               " has no valid diameter in the tool table (D " +
                               rt::format_shortest(entry->diameter_mm) + " mm)");
    if (o.type == CutType::kBall && !(radius > 0))
      throw GcodeError(at, "tool T" + std::to_string(ctx.tool) +
                               " has diameter 0 in the tool table: a ball end mill needs a "
                               "radius > 0 (its D word)");
    // 1 nm: the digits a person or printf("%f") writes, not a different tool.
    if (o.tool_radius_mm && std::fabs(*o.tool_radius_mm - radius) > 1e-6)
      throw RewriteError(
          "the tool radius given (" + rt::format_shortest(*o.tool_radius_mm) +
          " mm) differs from the tool table's for tool T" + std::to_string(ctx.tool) + " (D " +
          rt::format_shortest(entry->diameter_mm) + " mm, radius " + rt::format_shortest(radius) +
          " mm; first used on " + at.file + ":" + std::to_string(at.line) + ")");
    radii[ctx.tool] = radius;
  }
  return radii;
}

// The parameter settings that stand for what each expansion set: the
// program is run again and its parameters compared before the expansion's
// first line and after its last (numbered ones up to #5000, the system's
// above are set by calls an expansion refuses; named ones new or changed).
std::map<int, std::vector<std::string>> parameters_set_by(const Expansions& expansions,
                                                          std::string_view text,
                                                          const std::string& name,
                                                          const InterpreterOptions& io) {
  std::map<int, std::vector<std::string>> out;
  if (expansions.empty()) return out;
  InterpreterOptions watch = io;
  std::map<int, ParameterValues> at;
  for (const auto& [first, e] : expansions) {
    watch.watch_lines.insert(first);
    watch.watch_lines.insert(e.last_line + 1);
  }
  watch.on_watch_line = [&](int line, const ParameterValues& v) { at[line] = v; };
  watch.on_call = [](const CanonCall&, const std::vector<std::string>&) {};
  Interpreter(watch).run_text(text, name);
  constexpr int kLastUserParameter = 5000;
  for (const auto& [first, e] : expansions) {
    const auto before = at.find(first), after = at.find(e.last_line + 1);
    if (before == at.end() || after == at.end()) continue;
    std::vector<std::string>& lines = out[first];
    for (int k = 1; k <= kLastUserParameter; ++k)
      if (after->second.numbered[k] != before->second.numbered[k])
        lines.push_back("#" + std::to_string(k) + " = " + exact(after->second.numbered[k]));
    for (const auto& [key, value] : after->second.named) {
      const auto was = before->second.named.find(key);
      if (was == before->second.named.end() || was->second != value)
        lines.push_back("#<" + key + "> = " + exact(value));
    }
  }
  return out;
}

RewriteResult run(std::string_view text, const std::string& name, const RewriteOptions& o,
                  const PrepareFn& prepare, const CorrectionFn& correction) {
  const Interpreter interpreter(o.interpreter);
  CanonProgram program = interpreter.run_text(text, name);
  const auto names = operation_names(program);
  if (std::find(names.begin(), names.end(), o.operation) == names.end()) {
    std::string list;
    for (const auto& n : names)
      list += (list.empty() ? "" : ", ") + n;
    throw RewriteError(
        name + ": operation '" + o.operation + "' is not in the program (" +
        (list.empty() ? std::string("no (OPERATION: NAME) comments") : "operations: " + list) +
        ")");
  }
  // G10 L1/L10/L11 change the tool table while the program runs; the
  // rewrite takes each tool's radius from the table given, so it refuses
  // them by name rather than correct with a radius the program replaced.
  for (const CanonCall& c : program.calls)
    if (std::holds_alternative<SetToolTableEntry>(c.op))
      throw GcodeError({file_of(program, c.context, name), c.context.line, 0},
                       "G10 L1/L10/L11 (tool table edit) in the program: the rewrite takes the "
                       "tool radii from the tool table given and cannot follow an edit; put the "
                       "values into the tool table file instead");
  const std::vector<RawLine> raw = split_raw_lines(text);
  std::vector<NurbsBlock> nurbs_blocks;
  const std::set<int> spline_lines = expand_splines(program, raw, name, o, nurbs_blocks);
  const std::map<int, double> radius_by_tool = tool_radii(program, name, o);
  std::vector<double> radii;
  for (const auto& [tool, radius] : radius_by_tool)
    radii.push_back(radius);
  std::sort(radii.begin(), radii.end());
  radii.erase(std::unique(radii.begin(), radii.end()), radii.end());
  const double reach_mm = prepare(radii);
  // Cutter radius compensation (docs/gcode.md): the output runs in G40, with
  // every compensated move written where the compensated tool goes, and the
  // first move after the G40 exit with all of X Y Z (it starts from the
  // compensated point). Moves that run more than once cannot be written so;
  // O-words around moves that run once (conditions, a subroutine called
  // once) stay as written.
  const bool expands_comp = std::any_of(program.calls.begin(), program.calls.end(),
                                        [](const CanonCall& c) { return c.context.cutter_comp; });
  std::map<int, long> comp_line_block;  // the one execution of each compensated line
  bool after_comp = false;              // the last move was compensated
  // A canned cycle (G73, G74, G81-G89) expands into several moves on one line:
  // the rewrite cannot keep the cycle word and refuses it by name. The
  // motion mode of a line is followed through the source text in order.
  auto refuse_canned_cycle = [&](const std::string& file, int line) {
    int mode = -1, mode_line = 0;
    for (int i = 1; i <= line && i <= static_cast<int>(raw.size()); ++i) {
      const int code = motion_code_of_line(raw[i - 1].content);
      if (code >= 0) mode = code, mode_line = i;
    }
    if (!is_canned_cycle(mode)) return;
    const std::string g = "G" + std::to_string(mode / 10);
    throw GcodeError(
        {file, line, 0},
        "canned cycle " + g +
            (mode_line == line ? std::string() : " (from line " + std::to_string(mode_line) + ")") +
            " makes several moves on one line: it cannot be rewritten; program "
            "the holes as G0/G1 moves or keep them outside the operation");
  };

  // Loops and calls written out move by move (expansion.hpp).
  const Expansions expansions = find_expansions(program, raw, name, o.operation, nurbs_blocks);
  const std::map<int, std::vector<std::string>> parameters_set =
      parameters_set_by(expansions, text, name, o.interpreter);
  // Motion calls per line of the main file outside them: a rewritten line
  // must make one.
  std::map<int, int> motions_per_line;
  std::map<int, long> block_of_line;  // -1: the line runs more than once
  for (const CanonCall& c : program.calls)
    if (is_motion(c.op) && c.context.file == 0 && !expansion_at(expansions, c.context.outer_line)) {
      ++motions_per_line[c.context.line];
      const auto [at, fresh] = block_of_line.try_emplace(c.context.line, c.context.executed_block);
      if (!fresh && at->second != c.context.executed_block) at->second = -1;
    }
  // A, C on every expanded move when the program moves them at all.
  const bool program_uses_ac =
      std::any_of(program.calls.begin(), program.calls.end(), [](const CanonCall& c) {
        if (!is_motion(c.op)) return false;
        const Axes6 e = end_of(c.op);
        return e.a != 0 || e.c != 0;
      });

  RewriteSummary s;
  s.reach_mm = reach_mm;
  s.tool_radii_mm.assign(radius_by_tool.begin(), radius_by_tool.end());
  s.lines_in = static_cast<int>(raw.size());
  double sum_mm = 0;
  std::map<int, PlannedLine> plan;  // by 1-based line
  // G1 points written for the current line: a G5 line's chords add up.
  int points_line = 0;
  double points_on_line = 0, points_written = 0;
  std::map<int, RewrittenLine> expected;
  // Lines of another operation kept as they are, after a G1 back from a
  // corrected point to the original one: where that G1 ends.
  std::map<int, ReturnMove> returns;
  ToolPath path(o.kinematics);
  double feed_upm = 0;
  // The feed in force before the current line: the output has the same
  // there, since every line before was copied or written with that feed.
  double feed_before_line = 0;
  int line_file = -1, line_no = -1;
  int orig_mode = -1, out_mode = -1;
  bool displaced = false;  // the output's position differs from the original's
  // ... in A or C (a field's rotation): the next rapid, in the operation or
  // after it, brings them back.
  bool turned = false;

  // Canned cycles (docs/rewrite.md): a cycle line of the operation keeps its
  // cycle; its hole and bottom (X Y Z) are written where the correction at
  // the hole's bottom puts them. The moves of one execution of a cycle line
  // are gathered, then planned together.
  struct CycleMove {
    ToolPath::Move move;
    bool feed;
  };
  std::vector<CycleMove> cycle_moves;
  CallContext cycle_ctx;
  std::set<int> cycle_lines_planned;
  bool back_bores_rewritten = false;  // a G87 line of the operation was written
  // A cycle line was written with another hole or bottom: the cycle's later
  // lines, which take X Y Z from it, are written with their own.
  bool cycle_words_pending = false;
  auto plan_cycle_line = [&] {
    const CallContext& ctx = cycle_ctx;
    const int line = ctx.line;
    const std::string file = file_of(program, ctx, name);
    const bool in_op = ctx.operation == o.operation;
    const std::string g = "G" + std::to_string(ctx.canned_cycle / 10);
    if (!cycle_lines_planned.insert(line).second)
      throw GcodeError({file, line, 0}, "canned cycle " + g +
                                            " line runs more than once (loop or subroutine): it "
                                            "cannot be rewritten");
    // G87 back bores upwards from the bottom (Z, below the part) to K: the
    // cut is at K, where the correction is taken; X Y and K are written
    // corrected, Z and the entry offset I J as they were.
    const bool back_boring = ctx.canned_cycle == 870;
    if (back_boring && ctx.cycle_plane != Plane::kXY)
      throw GcodeError({file, line, 0},
                       "canned cycle G87 (back boring) outside G17: the rewrite corrects it in "
                       "the XY plane only");
    if (ctx.cycle_incremental)
      throw GcodeError({file, line, 0}, "canned cycle " + g +
                                            " in G91 (incremental distance): its hole and depth "
                                            "are relative and cannot be corrected; program it "
                                            "in G90");
    const int normal = ctx.cycle_plane == Plane::kXY ? 2 : ctx.cycle_plane == Plane::kXZ ? 1 : 0;
    // The hole's bottom: the deepest end of a feed (R lies above the bottom);
    // G87's cut: the highest.
    const ToolPath::Move* bottom = nullptr;
    const ToolPath::Move* top = nullptr;
    for (const CycleMove& m : cycle_moves) {
      if (!m.feed) continue;
      const double h = path.to_program(m.move.end, ctx)[normal];
      if (!bottom || h < path.to_program(bottom->end, ctx)[normal]) bottom = &m.move;
      if (!top || h > path.to_program(top->end, ctx)[normal]) top = &m.move;
    }
    if (!bottom) throw GcodeError({file, line, 0}, "canned cycle " + g + " without a feed move");
    const Vec5 p = back_boring ? top->end : bottom->end;
    Correction corr;
    if (in_op) {
      corr = correction(path.tool_point(p, ctx), ctx, radius_by_tool.at(ctx.tool));
    }
    // The hole is drilled along the tool as it stands: a rotation part of
    // the correction is not applied (docs/rewrite.md).
    const bool shifts = corr.shift_mm != Eigen::Vector3d::Zero();
    if (!shifts && !displaced && !cycle_words_pending && o.keep_unchanged_moves) {
      if (in_op) ++s.moves_kept;
      return;
    }
    const Vec5 corrected = shifts ? path.shifted(p, ctx, corr.shift_mm) : p;
    const Axes6 q = path.to_program(corrected, ctx);
    const LineWords words = split_cycle_line(raw[line - 1].content, file, line, back_boring);
    const int decimals = o.decimals > 0 ? o.decimals : ctx.units == LengthUnits::kInch ? 5 : 4;
    std::string axis_words;
    RewrittenLine rl;
    rl.context = ctx;
    rl.cycle_normal_axis = normal;
    rl.expected.push_back(q);
    const char letters[] = {'X', 'Y', 'Z'};
    for (int ax = 0; ax < 3; ++ax) {
      const std::string v = shifts ? rt::format_fixed(q[ax], decimals) : exact(q[ax]);
      if (back_boring && ax == 2) {
        axis_words += " Z" + exact(path.to_program(bottom->end, ctx)[2]) + " K" + v;
      } else {
        axis_words += std::string(axis_words.empty() ? "" : " ") + letters[ax] + v;
      }
      rl.expected[0][ax] = std::strtod(v.c_str(), nullptr);
    }
    PlannedLine pl;
    pl.moves.push_back(with_words_before_comment(words.residual, axis_words));
    plan[line] = std::move(pl);
    expected[line] = std::move(rl);
    if (in_op && corr.covered) ++s.points_covered;
    if (in_op && corr.compensated) {
      ++s.points_compensated;
      const double mag = corr.shift_mm.norm();
      s.max_compensation_mm = std::max(s.max_compensation_mm, mag);
      sum_mm += mag;
    }
    if (in_op) ++s.holes_rewritten;
    if (in_op && back_boring) back_bores_rewritten = true;
    cycle_words_pending = shifts;
    displaced = shifts;
  };
  auto flush_cycle = [&] {
    if (cycle_moves.empty()) return;
    plan_cycle_line();
    cycle_moves.clear();
  };

  // A feed of the operation cut into G1 points of at most a step, each
  // corrected (densify and compensate).
  struct Densified {
    int n = 0;
    std::vector<Vec5> points;
    std::vector<Correction> corrections;
    bool all_zero = true, rotated = false;
  };
  auto densify = [&](const ToolPath::Move& move, const CallContext& ctx, const std::string& file) {
    const double radius_mm = radius_by_tool.at(ctx.tool);
    const double pieces = std::max(pieces_for_step(path, move, ctx, o, radius_mm),
                                   static_cast<double>(pieces_for_chord(move, o)));
    if (ctx.line != points_line) {
      points_line = ctx.line;
      points_on_line = 0;
    }
    points_on_line += pieces;
    if (!(points_on_line <= kMaxPiecesPerMove))
      throw GcodeError({file, ctx.line, 0},
                       rt::format_printf("move would be written as %s%.3g G1 points of at most %g "
                                         "mm (more than %.0f): it is longer than any part's move",
                                         points_on_line > pieces ? "at least " : "", points_on_line,
                                         o.step_mm, kMaxPiecesPerMove));
    points_written += pieces;
    if (!(points_written <= o.max_points))
      throw GcodeError({file, ctx.line, 0},
                       rt::format_printf("the operation's feed moves up to here need "
                                         "%.3g G1 points, more than the limit of %.0f",
                                         points_written, o.max_points));
    const int n = static_cast<int>(pieces);
    std::vector<Vec5> points(n);
    std::vector<Correction> corrections(n);
    bool all_zero = true, rotated = false;
    for (int k = 1; k <= n; ++k) {
      const Vec5 p = ToolPath::at(move, static_cast<double>(k) / n);
      const Correction corr = correction(path.tool_point(p, ctx), ctx, radius_mm);
      corrections[k - 1] = corr;
      if (corr.shift_mm != Eigen::Vector3d::Zero() || corr.rotation_rad != Eigen::Vector3d::Zero())
        all_zero = false;
      if (corr.rotation_rad != Eigen::Vector3d::Zero()) {
        double shortfall_rad = 0.0;
        points[k - 1] = path.corrected(p, ctx, corr.shift_mm, corr.rotation_rad, shortfall_rad);
        rotated = rotated || points[k - 1][3] != p[3] || points[k - 1][4] != p[4];
        ++s.points_rotated;
        s.max_rotation_rad = std::max(s.max_rotation_rad, corr.rotation_rad.norm());
        s.max_rotation_shortfall_rad = std::max(s.max_rotation_shortfall_rad, shortfall_rad);
      } else {
        points[k - 1] =
            corr.shift_mm == Eigen::Vector3d::Zero() ? p : path.shifted(p, ctx, corr.shift_mm);
      }
    }
    return Densified{n, std::move(points), std::move(corrections), all_zero, rotated};
  };
  // Counted for moves kept as they are too: what tells a field without a
  // valid node there from one that does not reach the operation at all.
  auto count_covered = [&](const std::vector<Correction>& corrections) {
    for (const Correction& corr : corrections)
      s.points_covered += corr.covered ? 1 : 0;
  };
  auto count_corrections = [&](const std::vector<Correction>& corrections) {
    for (const Correction& corr : corrections) {
      for (int k = 0; k < 4; ++k)
        s.blend_points[k] += corr.blends[k];
      if (!corr.compensated) continue;
      ++s.points_compensated;
      const double mag = corr.shift_mm.norm();
      s.max_compensation_mm = std::max(s.max_compensation_mm, mag);
      sum_mm += mag;
    }
  };

  // The expansion being written: its moves go onto its first line, in order.
  struct OpenExpansion {
    const Expansion* e = nullptr;
    double out_feed = 0;  // the feed in force in the new program
    bool first_move = true;
    long moves = 0;
    // G91 in force at the last call inside (a change of mode makes a call,
    // the interpreter's note).
    bool incremental = false;
    bool inverse_time = false;  // G93 in force at the last call inside
    double sync_k = 0;          // > 0: the feeds follow the spindle (G33 K)
  };
  bool incremental_before = false;       // G91 in force at the last call before
  bool incremental_before_line = false;  // ... before the current line's calls
  OpenExpansion ex;
  std::set<int> closed_expansions;
  std::map<int, long> expanded_moves;  // by first line
  // Leaves the expansion: the feed and distance mode the original has at
  // its end.
  auto close_expansion = [&] {
    PlannedLine& pl = plan[ex.e->first_line];
    if (const auto it = parameters_set.find(ex.e->first_line); it != parameters_set.end())
      pl.moves.insert(pl.moves.end(), it->second.begin(), it->second.end());
    // In G93 every feed line carries its own F: none is restored.
    if (!ex.inverse_time && ex.out_feed != feed_upm) pl.moves.push_back("F" + feed_text(feed_upm));
    if (ex.incremental) pl.moves.push_back("G91");
    incremental_before = ex.incremental;
    expanded_moves[ex.e->first_line] = ex.moves;
    closed_expansions.insert(ex.e->first_line);
    ++s.expansions;
    s.expanded_moves += ex.moves;
    ex = OpenExpansion{};
  };
  auto expansion_error = [&](const CanonCall& c, const std::string& what) -> GcodeError {
    const Expansion& e = *ex.e;
    return GcodeError(
        {file_of(program, c.context, name), c.context.line, 0},
        what + ", inside " + e.what + " (lines " + std::to_string(e.first_line) + "-" +
            std::to_string(e.last_line) + "), which the rewrite writes out move by move (" + e.why +
            "): an expansion writes moves, feeds, dwells, planes, path modes, units, tool "
            "changes and length offsets, spindle, coolant, work offsets, outputs, override "
            "switches, stops, logs and comments only");
  };
  // One call inside an expansion.
  // `cycle_end`: a canned cycle's move, written to that end (program units).
  long last_expanded_block = -1;  // the block of the last other call written
  // A SET_G5X_OFFSET written inside an expansion, until its block's
  // SET_XY_ROTATION tells a selection (with SET_G92_OFFSET) from a G10 L2.
  struct OpenG5x {
    long block = -1;
    size_t written_at = 0;  // its line in the expansion's moves
    int index = 0;
    Axes6 offset;
    bool with_g92 = false;
  };
  OpenG5x g5x_open;
  long m6_block = -1;  // the block of the last M6 written inside an expansion
  auto expand_call = [&](const CanonCall& c, const Axes6* cycle_end = nullptr) {
    const CallContext& ctx = c.context;
    ex.incremental = ctx.incremental;
    ex.inverse_time = ctx.feed_mode == FeedMode::kInverseTime;
    const int first = ex.e->first_line;
    PlannedLine& pl = plan[first];
    RewrittenLine& rl = expected[first];
    if (rl.last_line == 0) {
      rl.context = ctx;
      rl.context.line = first;
      rl.last_line = ex.e->last_line;
    }
    if (!is_motion(c.op)) {
      if (std::holds_alternative<SetFeedRate>(c.op)) return;
      if ((std::holds_alternative<StopSpindle>(c.op) || std::holds_alternative<ChangeTool>(c.op)) &&
          m6_block == ctx.executed_block) {
        rl.others.push_back(format_rs274(c.op, check_format()));  // the M6 written makes it
        return;
      }
      std::string text;
      if (const auto* m = std::get_if<Comment>(&c.op)) {
        if (m->sets_system != 0) {
          // G10 L2/L20 of a system not in use: written as the G10 L2 that
          // gives that system the origin and rotation the original gave it.
          if (m->sets_system > 9 || m->system_origin.b != 0)
            throw expansion_error(c, "this line sets the origin of coordinate system " +
                                         std::to_string(m->sets_system) + " with a B offset");
          Axes6 unused;
          pl.moves.push_back("G10 L2 P" + std::to_string(m->sets_system) +
                             exact_words(m->system_origin, true, true, unused) + " R" +
                             exact(m->system_rotation_deg));
          // Its COMMENT is an interpreter note, which the self-check does not
          // compare; the selection of that system later does.
          last_expanded_block = ctx.executed_block;
          return;
        }
        // The interpreter's own notes of a mode change come from the mode
        // words the expansion writes (G90, G91), not from a copy.
        if (is_interpreter_note(*m)) return;
        text = "(" + m->text + ")";
      } else if (const auto* m = std::get_if<Message>(&c.op)) {
        text = "(MSG," + m->text + ")";
      } else if (const auto* d = std::get_if<Dwell>(&c.op)) {
        text = "G4 P" + exact(d->seconds);
      } else if (const auto* p = std::get_if<SelectPlane>(&c.op)) {
        text = p->plane == Plane::kXY ? "G17" : p->plane == Plane::kXZ ? "G18" : "G19";
      } else if (const auto* m = std::get_if<SetMotionControlMode>(&c.op)) {
        text = m->mode == PathMode::kExactStop   ? "G61.1"
               : m->mode == PathMode::kExactPath ? "G61"
                                                 : "G64 P" + exact(m->tolerance);
      } else if (const auto* sync = std::get_if<SpeedFeedSync>(&c.op)) {
        // G33 makes START_SPEED_FEED_SYNC, its feed, STOP_SPEED_FEED_SYNC:
        // the feed is written as that G33 line (below).
        ex.sync_k = sync->on ? sync->units_per_rev : 0;
        rl.others.push_back(format_rs274(c.op, check_format()));
        return;
      } else if (const auto* fm = std::get_if<SetFeedMode>(&c.op)) {
        text = fm->mode == FeedMode::kInverseTime          ? "G93"
               : fm->mode == FeedMode::kUnitsPerRevolution ? "G95"
                                                           : "G94";
        // A change of feed mode clears F: the next feed line writes its own.
        ex.out_feed = std::numeric_limits<double>::quiet_NaN();
      } else if (const auto* sp = std::get_if<SetSpindleSpeed>(&c.op)) {
        // G96 makes SET_SPINDLE_MODE then SET_SPINDLE_SPEED: its S goes onto
        // the G96 line just written, which LinuxCNC refuses without one.
        if (!pl.moves.empty() && pl.moves.back().rfind("G96", 0) == 0 &&
            pl.moves.back().find(" S") == std::string::npos) {
          pl.moves.back() += " S" + exact(sp->rpm);
          rl.others.push_back(format_rs274(c.op, check_format()));
          return;
        }
        text = "S" + exact(sp->rpm);
      } else if (const auto* m = std::get_if<SetSpindleMode>(&c.op)) {
        // rs274 passes 1e30 for a G96 without D.
        text = !m->constant_surface_speed ? "G97"
               : m->css_max_rpm >= 1e29   ? "G96"
                                          : "G96 D" + exact(m->css_max_rpm);
      } else if (const auto* st = std::get_if<StartSpindle>(&c.op)) {
        text = st->clockwise ? "M3" : "M4";
      } else if (std::holds_alternative<StopSpindle>(c.op)) {
        text = "M5";
      } else if (const auto* k = std::get_if<Coolant>(&c.op)) {
        if (k->on) {
          text = k->kind == Coolant::kMist ? "M7" : "M8";
        } else if (k->kind == Coolant::kMist) {
          text = "M9";  // M9 makes MIST_OFF then FLOOD_OFF
        } else {
          if (pl.moves.empty() || pl.moves.back() != "M9" || rl.others.empty() ||
              rl.others.back() != format_rs274(Coolant{Coolant::kMist, false}, check_format()))
            throw expansion_error(c, "this line makes FLOOD_OFF without MIST_OFF");
          rl.others.push_back(format_rs274(c.op, check_format()));
          return;
        }
      } else if (const auto* q = std::get_if<SetNaivecamTolerance>(&c.op)) {
        // G64 makes both calls: its Q goes onto the G64 line just written.
        if (pl.moves.empty() || pl.moves.back().rfind("G64 P", 0) != 0)
          throw expansion_error(c, "this line makes SET_NAIVECAM_TOLERANCE without G64");
        pl.moves.back() += " Q" + exact(q->tolerance);
        rl.others.push_back(format_rs274(c.op, check_format()));
        return;
      } else if (const auto* b = std::get_if<OutputBit>(&c.op); b) {
        // M62/M63 switch with the next move: written before its first line.
        text = std::string(b->synchronized ? (b->on ? "M62" : "M63") : (b->on ? "M64" : "M65")) +
               " P" + std::to_string(b->index);
      } else if (const auto* v = std::get_if<OutputValue>(&c.op); v) {
        text = std::string(v->synchronized ? "M67" : "M68") + " E" + std::to_string(v->index) +
               " Q" + exact(v->value);
      } else if (const auto* f = std::get_if<FeedOverride>(&c.op); f) {
        // M48/M49 make both override calls; M50 and M51 one each.
        text = std::string("M50 P") + (f->enabled ? "1" : "0");
      } else if (const auto* f = std::get_if<SpeedOverride>(&c.op); f) {
        text = std::string("M51 P") + (f->enabled ? "1" : "0");
      } else if (const auto* f = std::get_if<AdaptiveFeed>(&c.op)) {
        text = std::string("M52 P") + (f->enabled ? "1" : "0");
      } else if (const auto* f = std::get_if<FeedHold>(&c.op)) {
        text = std::string("M53 P") + (f->enabled ? "1" : "0");
      } else if (const auto* st = std::get_if<ProgramStop>(&c.op); st) {
        text = st->optional ? "M1" : "M0";
      } else if (const auto* o19 = std::get_if<OrientSpindle>(&c.op)) {
        // G87's orient prints LinuxCNC's CANON_DIRECTION, 2 for a clockwise
        // spindle: the call M19 P2 makes. M19 has no P3.
        if (o19->m19_direction < 0 && !o19->clockwise)
          throw expansion_error(c,
                                "this line orients the spindle counter-clockwise for G87 (M4): "
                                "ORIENT_SPINDLE(..., 3) has no M19 form");
        text = "M19 R" + exact(o19->degrees) + " P" +
               std::to_string(o19->m19_direction >= 0 ? o19->m19_direction : 2);
      } else if (const auto* w = std::get_if<WaitOrientComplete>(&c.op)) {
        // M19 R.. Q.. makes both calls: the Q goes onto that M19 line.
        if (!pl.moves.empty() && pl.moves.back().rfind("M19 R", 0) == 0 &&
            last_expanded_block == ctx.executed_block) {
          pl.moves.back() += " Q" + exact(w->timeout_s);
          rl.others.push_back(format_rs274(c.op, check_format()));
          return;
        }
        text = "M19 Q" + exact(w->timeout_s);
      } else if (const auto* g5x = std::get_if<SetG5xOffset>(&c.op)) {
        // G54 ... G59.3 make SET_G5X_OFFSET, SET_G92_OFFSET, SET_XY_ROTATION;
        // G10 L2/L20 of the system in use SET_G5X_OFFSET, SET_XY_ROTATION.
        // Written as the selection, made a G10 L2 below when no G92 call
        // follows in the block.
        static const char* const kSystems[] = {"G54", "G55",   "G56",   "G57",  "G58",
                                               "G59", "G59.1", "G59.2", "G59.3"};
        if (g5x->index < 1 || g5x->index > 9 || g5x->offset.b != 0)
          throw expansion_error(c, "this line makes SET_G5X_OFFSET(" + std::to_string(g5x->index) +
                                       ") with a B offset");
        text = kSystems[g5x->index - 1];
        g5x_open = {ctx.executed_block, pl.moves.size(), g5x->index, g5x->offset, false};
      } else if (std::holds_alternative<SetG92Offset>(c.op) &&
                 g5x_open.block == ctx.executed_block) {
        g5x_open.with_g92 = true;  // the selection's own call
        rl.others.push_back(format_rs274(c.op, check_format()));
        return;
      } else if (const auto* rot = std::get_if<SetXYRotation>(&c.op)) {
        if (g5x_open.block != ctx.executed_block)
          throw expansion_error(c, "this line makes SET_XY_ROTATION alone");
        if (!g5x_open.with_g92) {
          Axes6 unused;
          pl.moves[g5x_open.written_at] = "G10 L2 P" + std::to_string(g5x_open.index) +
                                          exact_words(g5x_open.offset, true, true, unused) + " R" +
                                          exact(rot->degrees);
        }
        g5x_open = {};
        rl.others.push_back(format_rs274(c.op, check_format()));
        return;
      } else if (const auto* t = std::get_if<SelectTool>(&c.op)) {
        text = "T" + std::to_string(t->tool);
      } else if (std::holds_alternative<StartChange>(c.op)) {
        // M6 makes START_CHANGE, STOP_SPINDLE_TURNING, CHANGE_TOOL.
        text = "M6";
        m6_block = ctx.executed_block;
      } else if (const auto* n = std::get_if<ChangeToolNumber>(&c.op)) {
        text = "M61 Q" + std::to_string(n->tool);
      } else if (const auto* tlo = std::get_if<UseToolLengthOffset>(&c.op)) {
        // G43 H, G43.1, G43.2 and G49 make USE_TOOL_LENGTH_OFFSET with the
        // offsets now in force: written as the G43.1 that sets them all
        // (G49 when they are zero).
        if (tlo->offset.b != 0)
          throw expansion_error(c, "this line makes USE_TOOL_LENGTH_OFFSET with a B offset");
        Axes6 unused;
        text = tlo->offset == Axes6{} ? std::string("G49")
                                      : "G43.1" + exact_words(tlo->offset, true, true, unused);
      } else if (const auto* u = std::get_if<UseLengthUnits>(&c.op)) {
        text = u->units == LengthUnits::kInch ? "G20" : "G21";
      } else if (const auto* g92 = std::get_if<SetG92Offset>(&c.op)) {
        // G52, G92 and G92.1-G92.3 make SET_G92_OFFSET with the offset now
        // in force: written as the G52 that sets it on every axis (the moves
        // after it are written in the frame it gives, as they came).
        if (g92->offset.b != 0)
          throw expansion_error(c, "this line makes SET_G92_OFFSET with a B offset");
        Axes6 unused;
        text = "G52" + exact_words(g92->offset, true, true, unused);
      } else if (const auto* lf = std::get_if<LogFile>(&c.op)) {
        text = lf->kind == LogFile::kOpen     ? "(LOGOPEN," + lf->text + ")"
               : lf->kind == LogFile::kAppend ? "(LOGAPPEND," + lf->text + ")"
               : lf->kind == LogFile::kClose  ? std::string("(LOGCLOSE)")
                                              : "(LOG," + lf->text + ")";
      } else if (std::holds_alternative<ProbeSwitch>(c.op) ||
                 std::holds_alternative<StraightProbe>(c.op)) {
        throw expansion_error(c, std::string("this line makes ") + call_name(c.op) +
                                     " (probing: where the probe stops, and so what follows, "
                                     "is known only on the machine)");
      } else {
        throw expansion_error(c, std::string("this line makes ") + call_name(c.op));
      }
      pl.moves.push_back(text);
      rl.others.push_back(format_rs274(c.op, check_format()));
      last_expanded_block = ctx.executed_block;
      return;
    }
    if (std::holds_alternative<NurbsFeed>(c.op)) throw expansion_error(c, "NURBS block here");
    if (ctx.spline != SplineMode::kNone) throw expansion_error(c, "BSPLINE/CSPLINE point here");
    const bool feed = !std::holds_alternative<StraightTraverse>(c.op);
    const bool inverse_time = feed && ctx.feed_mode == FeedMode::kInverseTime;
    path.rebase(ctx);
    const ToolPath::Move move = std::holds_alternative<ArcFeed>(c.op)
                                    ? path.arc_to(std::get<ArcFeed>(c.op), ctx)
                                    : path.line_to(end_of(c.op), ctx);
    orig_mode = motion_mode(c.op);
    const bool in_op = ctx.operation == o.operation;
    if (in_op) ++s.moves_read;
    const auto context_index = static_cast<std::uint32_t>(rl.contexts.size());
    rl.contexts.push_back(ctx);
    const int decimals = o.decimals > 0 ? o.decimals : ctx.units == LengthUnits::kInch ? 5 : 4;
    // A line of the expansion: X Y Z (A C) exactly, or rounded when corrected.
    // `pieces`: the original move is written as that many lines; in G93 each
    // takes its share of the move's time 1/F.
    auto write = [&](const Axes6& q, bool traverse, bool corrected, bool with_ac, size_t pieces) {
      std::string line = ex.first_move && incremental_before ? "G90 " : "";
      ex.first_move = false;
      const bool sync = !traverse && ex.sync_k > 0;
      line += traverse ? "G0" : sync ? "G33" : "G1";
      Axes6 read = q;
      if (corrected) {
        const char letters[] = {'X', 'Y', 'Z', 'A', 'B', 'C'};
        for (int ax : {0, 1, 2, 3, 5}) {
          if ((ax == 3 || ax == 5) && !with_ac) continue;
          const std::string v = rt::format_fixed(q[ax], decimals);
          line += std::string(" ") + letters[ax] + v;
          read[ax] = std::strtod(v.c_str(), nullptr);
        }
      } else {
        line += exact_words(q, with_ac, with_ac, read);
      }
      double feed_at = feed_upm;
      if (sync) {
        line += " K" + exact(ex.sync_k);
      } else if (!traverse && inverse_time) {
        const std::string f = exact(ctx.inverse_time_f * static_cast<double>(pieces));
        line += " F" + f;
        feed_at = std::strtod(f.c_str(), nullptr);
      } else if (!traverse && ex.out_feed != feed_upm) {
        line += " F" + feed_text(feed_upm);
        ex.out_feed = feed_upm;
      }
      pl.moves.push_back(line);
      rl.expected.push_back(read);
      rl.traverse_at.push_back(traverse ? 1 : 0);
      rl.feed_at.push_back(feed_at);
      rl.context_at.push_back(context_index);
      ++ex.moves;
    };
    if (cycle_end) {
      const bool moved = *cycle_end != end_of(c.op);
      write(*cycle_end, !feed, moved, program_uses_ac || turned, 1);
      if (in_op) ++s.moves_kept;
      displaced = moved;
      turned = false;
    } else if (in_op && feed) {
      Densified d = densify(move, ctx, file_of(program, ctx, name));
      count_covered(d.corrections);
      count_corrections(d.corrections);
      const bool with_ac = program_uses_ac || d.rotated || turned;
      // A G33 move stays one line: each G33 waits for the spindle's index
      // pulse, so pieces would start the thread anew. Its end is corrected.
      if (ex.sync_k > 0) d.points.erase(d.points.begin(), d.points.end() - 1);
      for (const Vec5& p : d.points)
        write(path.to_program(p, ctx), false, true, with_ac, d.points.size());
      s.points_written += static_cast<long>(d.points.size());
      ++s.moves_rewritten;
      displaced = d.points.back() != move.end;
      turned = d.points.back()[3] != move.end[3] || d.points.back()[4] != move.end[4];
    } else {
      const bool with_ac = program_uses_ac || turned;
      // Another operation's feed starts from the original point.
      // (In G93 that step takes as long as the move: any F will do.)
      if (feed && displaced) write(path.to_program(move.start, ctx), false, false, with_ac, 1);
      const int n = feed && ex.sync_k == 0 ? pieces_for_chord(move, o) : 1;
      for (int k = 1; k <= n; ++k)
        write(k == n ? end_of(c.op)
                     : path.to_program(ToolPath::at(move, static_cast<double>(k) / n), ctx),
              !feed, false, with_ac, static_cast<size_t>(n));
      if (in_op) ++s.moves_kept;
      displaced = false;
      turned = false;
    }
    path.finish(move);
    out_mode = feed ? (ex.sync_k > 0 ? 33 : 1) : 0;
    // Compensated moves are written where the compensated tool went; the
    // first move after the G40 exit, after the expansion, with all of X Y Z.
    after_comp = ctx.cutter_comp;
    cycle_words_pending = false;
  };

  // A line kept as it is after a move back from a corrected point to the
  // original one (pl: that move, then the line).
  auto keep_after_return = [&](int line, PlannedLine pl, const Axes6& back, bool traverse,
                               const ToolPath::Move& move) {
    pl.last_verbatim = true;
    plan[line] = std::move(pl);
    returns[line] = {back, traverse};
    ++s.returns_written;
    path.finish(move);
    out_mode = orig_mode;
    displaced = false;
    turned = false;
  };

  // The calls of one canned-cycle block inside an expansion: its holes are
  // corrected as on a cycle line that runs once, by the correction at each
  // hole's bottom (the cycle is written out as its moves).
  std::vector<const CanonCall*> expanded_cycle;
  auto flush_expanded_cycle = [&] {
    if (expanded_cycle.empty()) return;
    std::vector<Axes6> ends(expanded_cycle.size());
    std::vector<bool> is_move(expanded_cycle.size(), false);
    const CanonCall& head = *expanded_cycle.front();
    const CallContext& cctx = head.context;
    // G87 goes down beside the hole (the entry offset I J) and back bores
    // upwards: every move of the block belongs to its one hole, and the cut
    // is the feed's top (K), where the correction is taken.
    const bool back_boring = cctx.canned_cycle == 870;
    const int normal = cctx.cycle_plane == Plane::kXY ? 2 : cctx.cycle_plane == Plane::kXZ ? 1 : 0;
    path.rebase(cctx);
    size_t k = 0;
    while (k < expanded_cycle.size()) {
      // A hole: the moves that end over the same point of the plane.
      size_t end = k;
      const Axes6* hole = nullptr;
      const Axes6* cut = nullptr;  // the bottom (G87: the top) of the feeds
      for (; end < expanded_cycle.size(); ++end) {
        const CanonCall& c = *expanded_cycle[end];
        if (!is_motion(c.op)) continue;
        const bool feed = !std::holds_alternative<StraightTraverse>(c.op);
        const Axes6 e = end_of(c.op);
        bool same = true;
        for (int ax = 0; ax < 3; ++ax)
          if (ax != normal && hole && e[ax] != (*hole)[ax]) same = false;
        if (!same && back_boring && feed)
          throw expansion_error(c,
                                "canned cycle G87 (back boring) on this line bores more than "
                                "one hole (L repeats in G91)");
        if (!same && !back_boring) break;
        is_move[end] = true;
        ends[end] = e;
        if (feed && !hole) hole = &ends[end];
        if (!back_boring && !hole) hole = &ends[end];
        if (feed &&
            (!cut || (back_boring ? e[normal] > (*cut)[normal] : e[normal] < (*cut)[normal])))
          cut = &ends[end];
      }
      if (cut && cctx.operation == o.operation) {
        const Axes6 b = *cut;
        const Vec5 p = path.line_to(b, cctx).end;
        const Correction corr =
            correction(path.tool_point(p, cctx), cctx, radius_by_tool.at(cctx.tool));
        if (corr.shift_mm != Eigen::Vector3d::Zero()) {
          const Axes6 q = path.to_program(path.shifted(p, cctx, corr.shift_mm), cctx);
          for (size_t i = k; i < end; ++i) {
            if (!is_move[i]) continue;
            const bool feed = !std::holds_alternative<StraightTraverse>(expanded_cycle[i]->op);
            for (int ax = 0; ax < 3; ++ax)
              if (ax != normal)
                ends[i][ax] += q[ax] - b[ax];
              else if (ends[i][ax] == b[ax] && (feed || !back_boring))
                ends[i][ax] = q[ax];
          }
        }
        if (corr.covered) ++s.points_covered;
        if (corr.compensated) {
          ++s.points_compensated;
          const double mag = corr.shift_mm.norm();
          s.max_compensation_mm = std::max(s.max_compensation_mm, mag);
          sum_mm += mag;
        }
        ++s.expanded_holes;
      }
      k = std::max(end, k + 1);
    }
    for (size_t i = 0; i < expanded_cycle.size(); ++i)
      expand_call(*expanded_cycle[i], is_move[i] ? &ends[i] : nullptr);
    expanded_cycle.clear();
  };

  for (const CanonCall& c : program.calls) {
    const CallContext& ctx = c.context;
    const Expansion* expansion = expansion_at(expansions, ctx.outer_line);
    const bool cycle_move = is_motion(c.op) && ctx.canned_cycle != 0;
    if (!expanded_cycle.empty() &&
        (expansion != ex.e ||
         ctx.executed_block != expanded_cycle.front()->context.executed_block ||
         (is_motion(c.op) && !cycle_move)))
      flush_expanded_cycle();
    if (ex.e && expansion != ex.e) close_expansion();
    path.observe(c);
    if (c.context.file != line_file || c.context.line != line_no) {
      line_file = c.context.file;
      line_no = c.context.line;
      feed_before_line = feed_upm;
      incremental_before_line = incremental_before;
    }
    if (expansion && !ex.e) {
      if (closed_expansions.count(expansion->first_line))
        throw GcodeError({name, expansion->first_line, 0},
                         expansion->what + " is written out move by move (" + expansion->why +
                             "), but its calls come out in two parts (held back by cutter "
                             "compensation before it?)");
      flush_cycle();
      ex.e = expansion;
      ex.out_feed = feed_upm;
    }
    if (const auto* f = std::get_if<SetFeedRate>(&c.op)) feed_upm = f->units_per_minute;
    if (expansion) {
      if (cycle_move || !expanded_cycle.empty())
        expanded_cycle.push_back(&c);
      else
        expand_call(c);
      continue;
    }
    incremental_before = ctx.incremental;
    if (!is_motion(c.op)) continue;
    if (!cycle_moves.empty() && ctx.executed_block != cycle_ctx.executed_block) flush_cycle();
    path.rebase(ctx);
    const ToolPath::Move move = std::holds_alternative<ArcFeed>(c.op)
                                    ? path.arc_to(std::get<ArcFeed>(c.op), ctx)
                                    : path.line_to(end_of(c.op), ctx);
    const int mode_before = orig_mode;
    orig_mode = motion_mode(c.op);
    const bool in_op = ctx.operation == o.operation;
    const bool feed = !std::holds_alternative<StraightTraverse>(c.op);
    if (in_op) ++s.moves_read;
    const std::string file = file_of(program, ctx, name);
    if (ctx.cutter_comp && ctx.file == 0) {
      const auto [first, fresh] = comp_line_block.try_emplace(ctx.line, ctx.executed_block);
      if (!fresh && first->second != ctx.executed_block)
        throw GcodeError({file, ctx.line, 0},
                         "move under cutter radius compensation on a line that runs more than "
                         "once (loop, or a subroutine called twice): the rewrite writes "
                         "compensated moves out one by one, where the tool goes each time");
    }
    if (expands_comp && (ctx.cutter_comp || after_comp) && !(in_op && feed)) {
      // A compensated move, or the first after the G40 exit, outside what
      // the operation corrects: written exactly where the tool goes.
      if (ctx.file != 0)
        throw GcodeError({file, ctx.line, 0},
                         "move under cutter radius compensation in a subroutine file: it "
                         "cannot be written out");
      if (!ctx.cutter_comp && motions_per_line[ctx.line] != 1)
        throw GcodeError({file, ctx.line, 0},
                         "the first move after the cutter compensation exit makes several "
                         "moves: it cannot be written out");
      const LineWords words = split_move_line(raw[ctx.line - 1].content, file, ctx.line);
      PlannedLine& pl = plan[ctx.line];
      RewrittenLine& rl = expected[ctx.line];
      if (pl.moves.empty()) pl.residual = words.residual;
      rl.context = ctx;
      rl.traverse = !feed;
      const int n = pieces_for_chord(move, o);
      const Axes6 start_prog = path.to_program(move.start, ctx);
      const Axes6 end_prog = end_of(c.op);
      const bool write_a = words.has_a || start_prog.a != end_prog.a;
      const bool write_c = words.has_c || start_prog.c != end_prog.c;
      for (int k = 1; k <= n; ++k) {
        const Axes6 q = k == n
                            ? end_prog
                            : path.to_program(ToolPath::at(move, static_cast<double>(k) / n), ctx);
        std::string line = words.block_delete ? "/" : "";
        line += feed ? "G1" : "G0";
        Axes6 expect = end_prog;
        line += exact_words(q, write_a, write_c, expect);
        if (feed && ctx.feed_mode == FeedMode::kInverseTime)
          line += " F" + feed_text(ctx.inverse_time_f * n);
        else if (feed && k == 1 && feed_before_line != feed_upm)
          line += " F" + feed_text(feed_upm);
        pl.moves.push_back(line);
        rl.expected.push_back(expect);
      }
      if (in_op) ++s.moves_kept;
      after_comp = ctx.cutter_comp;
      path.finish(move);
      out_mode = feed ? 1 : 0;
      displaced = false;
      continue;
    }
    if (ctx.canned_cycle != 0 && ctx.file == 0 && (in_op || cycle_words_pending)) {
      if (cycle_moves.empty()) cycle_ctx = ctx;
      cycle_moves.push_back({move, feed});
      path.finish(move);
      out_mode = orig_mode;
      after_comp = false;
      continue;
    }
    if (ctx.canned_cycle == 0) cycle_words_pending = false;
    const bool follows_comp = after_comp;  // starts from a compensated point
    after_comp = ctx.cutter_comp;
    if (!feed && displaced) {
      // A rapid after a compensated point, in the operation or the first
      // after it (the next operation's retract): written with all of X Y Z
      // (and A and C when they were turned), so the axes it does not name
      // come back to the original position.
      if (ctx.file != 0 || block_of_line[ctx.line] < 0)
        throw GcodeError({file, ctx.line, 0},
                         "rapid after a compensated move runs more than once or in a subroutine "
                         "file: the way back to the original point cannot be written before it");
      const std::string& source = raw[ctx.line - 1].content;
      std::optional<LineWords> split;
      const bool g91 = incremental_before_line;
      if (motions_per_line[ctx.line] == 1 && !g91 && !ctx.incremental) try {
          split = split_move_line(source, file, ctx.line);
        } catch (const GcodeError&) {
          // Words the rewrite cannot move (parameters, G53 ...): below.
        }
      if (!split) {
        // The line cannot take the original point in its words (it computes
        // them, moves in machine coordinates, makes several moves: G28, a
        // canned cycle ...): a G0 back to the original point is written
        // before it, and the line kept as it is.
        const bool block_delete = source.find_first_not_of(" \t") != std::string::npos &&
                                  source[source.find_first_not_of(" \t")] == '/';
        const Axes6 back = path.to_program(move.start, ctx);
        Axes6 expect = back;
        PlannedLine pl;
        pl.moves.push_back(std::string(block_delete ? "/" : "") + (g91 ? "G90 G0" : "G0") +
                           exact_words(back, turned, turned, expect));
        if (g91) pl.moves.push_back(block_delete ? "/G91" : "G91");
        pl.moves.push_back(source);
        keep_after_return(ctx.line, std::move(pl), expect, true, move);
        continue;
      }
      const LineWords& words = *split;
      const Axes6 end = end_of(c.op);
      PlannedLine pl;
      pl.residual = words.residual;
      RewrittenLine rl;
      rl.context = ctx;
      rl.traverse = true;
      Axes6 expect = end;
      std::string line = words.block_delete ? "/G0" : "G0";
      line += exact_words(end, words.has_a || turned, words.has_c || turned, expect);
      pl.moves.push_back(line);
      rl.expected.push_back(expect);
      plan[ctx.line] = std::move(pl);
      expected[ctx.line] = std::move(rl);
      ++s.rapids_rewritten;
      path.finish(move);
      out_mode = 0;
      displaced = false;
      turned = false;
      continue;
    }
    if (!in_op && feed && displaced) {
      // Another operation's feed right after a corrected point: a G1 back
      // to the original point is written before its line, which is kept as
      // it is, so the other operation cuts exactly what it did (an arc's
      // centre and a spline's control points assume the original start).
      const std::string& source = raw[ctx.line - 1].content;
      if (const auto* n = std::get_if<NurbsFeed>(&c.op);
          n && !line_has_g_code(source, 50) && !line_has_g_code(source, 51))
        throw GcodeError({file, ctx.line, 0},
                         "G5.2 NURBS block right after a corrected move: it would start from "
                         "the corrected point; put a move to its start (or a rapid) before it");
      if (ctx.file != 0 || motions_per_line[ctx.line] != 1)
        throw GcodeError({file, ctx.line, 0},
                         "feed after a compensated move makes several moves (loop, subroutine "
                         "or G28/G30): the way back to the original point cannot be written "
                         "before it; put a move to its start (or a rapid) before it");
      if (ctx.feed_mode == FeedMode::kInverseTime)
        throw GcodeError({file, ctx.line, 0},
                         "feed after a compensated move in G93 (inverse time): the way back to "
                         "the original point would need a time of its own; put a move to its "
                         "start (or a rapid) before it");
      bool explicit_motion = false;
      bool block_delete = source.find_first_not_of(" \t") != std::string::npos &&
                          source[source.find_first_not_of(" \t")] == '/';
      try {
        const LineWords words = split_move_line(source, file, ctx.line);
        explicit_motion = words.explicit_motion;
        block_delete = words.block_delete;
      } catch (const GcodeError&) {
        // Words the rewrite cannot move: the line is kept as it is anyway.
      }
      if (orig_mode != 1 && !explicit_motion)
        throw GcodeError({file, ctx.line, 0},
                         "feed after a compensated move continues a modal G" +
                             std::to_string(orig_mode) +
                             " without its G word: the G1 back to the original point written "
                             "before it would change its mode; write G" +
                             std::to_string(orig_mode) + " on the line");
      const Axes6 back = path.to_program(move.start, ctx);
      Axes6 expect = back;
      const std::string line =
          (block_delete ? "/G1" : "G1") + exact_words(back, turned, turned, expect);
      PlannedLine pl;
      pl.moves = {line, source};
      keep_after_return(ctx.line, std::move(pl), expect, false, move);
      continue;
    }
    if (!in_op || !feed) {
      path.finish(move);
      if (in_op) ++s.moves_kept;
      out_mode = orig_mode;
      displaced = false;
      continue;
    }
    if (ctx.file != 0)
      throw GcodeError({file, ctx.line, 0},
                       "move of operation '" + o.operation +
                           "' in a subroutine file: only the main program is rewritten");
    if (ctx.spline != SplineMode::kNone)
      throw GcodeError({file, ctx.line, 0},
                       "BSPLINE/CSPLINE point: spline moves cannot be rewritten as G1 moves");
    if (motions_per_line[ctx.line] != 1 && !ctx.cutter_comp && !spline_lines.count(ctx.line)) {
      refuse_canned_cycle(file, ctx.line);
      throw GcodeError({file, ctx.line, 0},
                       "line makes several moves in one run (G28/G30): it cannot be "
                       "rewritten");
    }

    // Densify and compensate.
    Densified d = densify(move, ctx, file);
    const int n = d.n;
    const std::vector<Vec5>& points = d.points;
    const std::vector<Correction>& corrections = d.corrections;
    const bool all_zero = d.all_zero, rotated = d.rotated;
    count_covered(corrections);
    const std::string& source = raw[ctx.line - 1].content;
    if (o.keep_unchanged_moves && all_zero && !displaced && !ctx.cutter_comp && !follows_comp &&
        !spline_lines.count(ctx.line)) {
      bool explicit_motion = false;
      try {
        explicit_motion = split_move_line(source, file, ctx.line).explicit_motion;
      } catch (const GcodeError&) {
      }
      if (explicit_motion || mode_before == out_mode) {
        path.finish(move);
        ++s.moves_kept;
        out_mode = orig_mode;
        continue;
      }
    }

    count_corrections(corrections);
    const LineWords words = split_move_line(source, file, ctx.line);
    PlannedLine pl;
    pl.residual = words.residual;
    RewrittenLine rl;
    rl.context = ctx;
    const Axes6 original_end = end_of(c.op);
    const Axes6 start_prog = path.to_program(move.start, ctx);
    const Axes6 end_prog = path.to_program(move.end, ctx);
    // A turned A or C (a field's rotation) is written on every point.
    const bool write_a = words.has_a || start_prog.a != end_prog.a || rotated;
    const bool write_c = words.has_c || start_prog.c != end_prog.c || rotated;
    const bool inverse_time = ctx.feed_mode == FeedMode::kInverseTime;
    for (int k = 0; k < n; ++k) {
      const Axes6 q = path.to_program(points[k], ctx);
      std::string line = words.block_delete ? "/" : "";
      if (k == 0 && out_mode != 1) line += "G1 ";
      Axes6 expect = original_end;
      auto word = [&](char letter, int axis, bool write) {
        if (!write) return;
        const int decimals = o.decimals > 0 ? o.decimals : ctx.units == LengthUnits::kInch ? 5 : 4;
        const std::string v = rt::format_fixed(q[axis], decimals);
        if (!line.empty() && line.back() != ' ' && line.back() != '/') line += ' ';
        line += letter + v;
        expect[axis] = std::strtod(v.c_str(), nullptr);
      };
      word('X', 0, true);
      word('Y', 1, true);
      word('Z', 2, true);
      word('A', 3, write_a);
      word('C', 5, write_c);
      // G93: each piece takes its share 1/n of the move's time 1/F.
      if (inverse_time)
        line += " F" + feed_text(ctx.inverse_time_f * n);
      else if (k == 0 && feed_before_line != feed_upm)
        line += " F" + feed_text(feed_upm);
      pl.moves.push_back(line);
      rl.expected.push_back(expect);
    }
    s.points_written += n;
    ++s.moves_rewritten;
    // Under cutter compensation a line may make two moves (a corner arc and
    // its move): both are written.
    PlannedLine& dst = plan[ctx.line];
    if (dst.moves.empty()) dst.residual = pl.residual;
    dst.moves.insert(dst.moves.end(), pl.moves.begin(), pl.moves.end());
    RewrittenLine& rdst = expected[ctx.line];
    rdst.context = rl.context;
    rdst.traverse = false;
    rdst.expected.insert(rdst.expected.end(), rl.expected.begin(), rl.expected.end());
    out_mode = 1;
    displaced = points.back() != move.end;
    turned = points.back()[3] != move.end[3] || points.back()[4] != move.end[4];
    path.finish(move);
  }
  flush_cycle();
  flush_expanded_cycle();
  if (ex.e) close_expansion();
  s.mean_compensation_mm = s.points_compensated > 0 ? sum_mm / s.points_compensated : 0.0;

  // Lines that switch compensation on without a move of their own lose
  // their G41/G42 words too; not those that run only inside written-out
  // loops and calls (a subroutine's definition no longer called).
  std::set<int> runs_outside_expansions;
  if (expands_comp && !expansions.empty())
    for (const CanonCall& c : program.calls)
      if (c.context.file == 0 && !expansion_at(expansions, c.context.outer_line))
        runs_outside_expansions.insert(c.context.line);
  if (expands_comp)
    for (size_t i = 0; i < raw.size(); ++i) {
      const int line = static_cast<int>(i) + 1;
      if (plan.count(line) || !has_cutter_comp_code(raw[i].content)) continue;
      if (!expansions.empty() && !runs_outside_expansions.count(line)) continue;
      plan[line].residual = split_move_line(raw[i].content, name, line).residual;
      expected[line].context.line = line;
    }

  // An expanded loop or call: a note on its first line, its other lines gone.
  for (const auto& [first, e] : expansions) {
    if (!expanded_moves.count(first)) continue;
    const std::string lines =
        e.last_line > first ? "lines " + std::to_string(first) + "-" + std::to_string(e.last_line)
                            : "line " + std::to_string(first);
    const auto set = parameters_set.find(first);
    const size_t n_set = set == parameters_set.end() ? 0 : set->second.size();
    const std::string set_text = n_set == 0 ? std::string()
                                            : " and the " + std::to_string(n_set) + " parameter" +
                                                  (n_set == 1 ? "" : "s") + " they set";
    const long n_moves = expanded_moves[first];
    const std::string moves_text =
        n_moves == 1 ? "the move it makes" : "the " + std::to_string(n_moves) + " moves they make";
    std::string note = "(truecut rewrite: " + lines + ", " + e.what + ", written out as " +
                       moves_text + set_text + ": " + e.why + ")";
    // A comment cannot hold parentheses.
    std::replace(note.begin() + 1, note.end() - 1, '(', '[');
    std::replace(note.begin() + 1, note.end() - 1, ')', ']');
    plan[first].residual = note;
    for (int line = first + 1; line <= e.last_line; ++line)
      plan[line] = PlannedLine{};
  }

  // Assemble: every other line byte for byte.
  RewriteResult r;
  std::vector<OutputLine> origin;
  const bool percent_first = !raw.empty() &&
                             raw[0].content.find_first_not_of(" \t") != std::string::npos &&
                             raw[0].content[raw[0].content.find_first_not_of(" \t")] == '%';
  auto header = [&] {
    if (!spline_lines.empty()) {
      r.text += "(truecut rewrite: " + std::to_string(spline_lines.size()) +
                " G5/G5.1 splines of operation " + o.operation + " written as G1 chords within " +
                rt::format_shortest(o.chord_tolerance_mm) + " mm of the curve, corrected)\n";
      origin.push_back({1, OutputLine::kResidual});
    }
    if (s.holes_rewritten > 0) {
      r.text += "(truecut rewrite: canned cycles kept: " + std::to_string(s.holes_rewritten) +
                " cycle lines of operation " + o.operation +
                " written with the hole and bottom X Y Z the correction at the bottom gives" +
                (back_bores_rewritten ? std::string("; G87 with the hole and back-bore height "
                                                    "X Y K the correction at K gives, Z kept")
                                      : std::string()) +
                ")\n";
      origin.push_back({1, OutputLine::kResidual});
    }
    if (!returns.empty()) {
      size_t rapids = 0;
      for (const auto& [line, back] : returns)
        rapids += back.traverse ? 1 : 0;
      const size_t feeds = returns.size() - rapids;
      if (feeds > 0)
        r.text += "(truecut rewrite: " + std::to_string(feeds) + " G1 move" +
                  (feeds == 1 ? "" : "s") +
                  " back from a corrected point to the original one written before the next "
                  "operation's first feed, which is kept as it is)\n";
      if (rapids > 0)
        r.text += "(truecut rewrite: " + std::to_string(rapids) + " G0 move" +
                  (rapids == 1 ? "" : "s") +
                  " back from a corrected point to the original one written before a rapid "
                  "whose line cannot take it, which is kept as it is)\n";
      for (int l = (feeds > 0) + (rapids > 0); l > 0; --l)
        origin.push_back({1, OutputLine::kResidual});
    }
    if (s.expansions > 0) {
      r.text +=
          "(truecut rewrite: " + std::to_string(s.expansions) +
          (s.expansions == 1 ? " loop, call or NURBS block" : " loops, calls or NURBS blocks") +
          " written out move by move, corrected: see the note at each)\n";
      origin.push_back({1, OutputLine::kResidual});
    }
    if (!expands_comp) return;
    r.text +=
        "(truecut rewrite: cutter radius compensation G41/G42 expanded: the moves under it are "
        "written where the compensated tool goes, the program runs in G40)\n";
    origin.push_back({1, OutputLine::kResidual});
  };
  if (!percent_first) header();
  for (size_t i = 0; i < raw.size(); ++i) {
    if (i == 1 && percent_first) header();
    const int line = static_cast<int>(i) + 1;
    auto it = plan.find(line);
    if (it == plan.end()) {
      r.text += raw[i].content;
      r.text += raw[i].terminator;
      origin.push_back({line, OutputLine::kVerbatim});
      continue;
    }
    const std::string& term = raw[i].terminator;
    const std::string inner = term.empty() ? "\n" : term;
    if (!it->second.residual.empty()) {
      r.text += it->second.residual + inner;
      origin.push_back({line, OutputLine::kResidual});
    }
    const auto& moves = it->second.moves;
    for (size_t k = 0; k < moves.size(); ++k) {
      r.text += moves[k];
      r.text += k + 1 < moves.size() ? inner : term;
      const bool verbatim = it->second.last_verbatim && k + 1 == moves.size();
      origin.push_back({line, verbatim ? OutputLine::kVerbatim : OutputLine::kMove});
    }
  }
  s.lines_out = static_cast<int>(origin.size());
  check_rewrite(r.text, CheckInput{program, expected, origin, o.interpreter, name, &returns});
  r.summary = s;
  return r;
}

}  // namespace
}  // namespace rewrite

RewriteResult rewrite_program(std::string_view text, const std::string& name,
                              const CompensationMatrixData& matrix, const RewriteOptions& o) {
  rewrite::check_options(o);
  // One search per radius of the operation's tools (nearly always one).
  std::map<double, rewrite::NeighbourSearch> searches;
  auto prepare = [&](const std::vector<double>& radii) {
    const CompensationMatrixData smoothed = rewrite::smooth_matrix(matrix, o.smoothing_radius_mm);
    // Without a feed move the points are still checked (and the reach found).
    const std::vector<double> built = radii.empty() ? std::vector<double>{0.0} : radii;
    for (double r : built)
      searches.try_emplace(r, smoothed, o.surfaces, o.type, r, o.reach_mm);
    return searches.begin()->second.reach_mm();
  };
  const bool swept = o.placement == MatrixPlacement::kEveryPass && o.type != CutType::kBall;
  auto fn = [&, swept](const rewrite::ToolPoint& tp, const CallContext& ctx, double radius_mm) {
    const rewrite::NeighbourSearch& search = searches.at(radius_mm);
    rewrite::Correction c;
    if (swept) {
      const double length = o.cutting_length_mm > 0    ? o.cutting_length_mm
                            : ctx.tool_offset_mm.z > 0 ? ctx.tool_offset_mm.z
                                                       : std::numeric_limits<double>::infinity();
      // Query points every half reach (with the default reach: the median
      // point spacing); on a disc at most 20 across its radius.
      const double band_mm = o.type == CutType::kFace
                                 ? std::max(search.reach_mm() / 2, radius_mm / 20)
                                 : search.reach_mm() / 2;
      const rewrite::SweptCorrection sc = rewrite::swept_correction(search, tp, length, band_mm);
      c.shift_mm = sc.correction_mm;
      c.compensated = c.covered = sc.blends > 0;
      c.blends = sc.blends_by_points;
      if (sc.blends == 0) c.blends[0] = 1;
      return c;
    }
    const rewrite::Nearest nn = search.nearest(tp);
    Eigen::Vector3d p[3], v[3];
    for (int i = 0; i < nn.count; ++i) {
      p[i] = search.position(nn.index[i]);
      v[i] = search.vector(nn.index[i]);
    }
    const BlendResult b =
        blend_compensation(std::span(p, nn.count), std::span(v, nn.count), nn.query_mm);
    c.shift_mm = b.correction_mm;
    c.compensated = c.covered = b.points_used > 0;
    c.blends[b.points_used] = 1;
    return c;
  };
  return rewrite::run(text, name, o, prepare, fn);
}

RewriteResult rewrite_program(std::string_view text, const std::string& name,
                              const rt::CorrectionField& field, const RewriteOptions& o) {
  rewrite::check_options(o);
  auto prepare = [](const std::vector<double>&) { return 0.0; };
  auto fn = [&](const rewrite::ToolPoint& tp, const CallContext& ctx, double) {
    const rt::FieldSample s = field.evaluate(ctx.tool, tp.tip_mm);
    if (s.status == rt::FieldStatus::kNoLayerForTool)
      throw RewriteError("the correction field has no layer for tool " + std::to_string(ctx.tool) +
                         " (operation '" + o.operation + "')");
    if (s.status == rt::FieldStatus::kNonFinite)
      throw RewriteError("the correction field gave a non-finite correction");
    rewrite::Correction c;
    c.covered = s.status == rt::FieldStatus::kOk;
    if (s.status == rt::FieldStatus::kOk && s.weight > 0) {
      c.shift_mm = s.correction_mm;
      c.rotation_rad = s.rotation_rad;
      c.compensated = true;
    }
    return c;
  };
  return rewrite::run(text, name, o, prepare, fn);
}

}  // namespace truecut::interp
