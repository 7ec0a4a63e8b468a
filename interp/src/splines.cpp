// G5 (cubic spline), G5.1 (quadratic B-spline) and G5.2 ... G5.3 (NURBS),
// as LinuxCNC 2.9's rs274 converts them: each becomes one NURBS_FEED call
// with its control points (docs/gcode.md "Splines G5.x").
#include <cmath>
#include <string>

#include "block_executor.hpp"

namespace truecut::interp {

namespace {

constexpr char kOffAxisLetters[4] = {'z', 'a', 'b', 'c'};

}  // namespace

void BlockExecutor::check_nurbs_closed(int column, const std::string& what) const {
  if (s_.nurbs.points.empty()) return;
  fail(column ? column : 1, "the G5.2 NURBS started at line " + std::to_string(s_.nurbs.line) +
                                " is not ended by G5.3 before " + what +
                                " (rs274 would drop its control points without moving)");
}

void BlockExecutor::spline(int code, const Axes6& target, int column, bool axis_words) {
  if (code == 50 || code == 51) {
    cubic_or_quadratic(code, target, column, axis_words);
  } else if (code == 52) {
    nurbs_point(target, column, axis_words);
  } else {
    nurbs_end(column, axis_words);
  }
}

void BlockExecutor::cubic_or_quadratic(int code, const Axes6& target, int column, bool axis_words) {
  const char* name = code == 50 ? "G5" : "G5.1";
  if (!axis_words) fail(column, std::string(name) + " needs X or Y (all axis words missing)");
  if (s_.comp.side != 0)
    fail(column, std::string("cannot convert a spline (") + name +
                     ") with cutter radius compensation on (G40 first)");
  if (s_.feed_mode == FeedMode::kUnitsPerMinute && s_.feed <= 0)
    fail(column, std::string(name) + " with a zero feed rate: program F before or on this line");
  if (s_.feed_mode == FeedMode::kInverseTime && !b_->has('f'))
    fail(column, std::string(name) + " in inverse-time feed (G93) needs an F word");
  if (s_.plane != Plane::kXY)
    fail(column, std::string("splines (") + name + ") must be in the XY plane (G17)");
  for (char l : kOffAxisLetters)
    if (b_->has(l))
      fail(column_of(l), std::string("splines (") + name + ") may not move Z, A, B or C");
  const Axes6 start = s_.program_position(move_base());
  const Axes6 end = s_.program_position(target);
  NurbsFeed n;
  n.end = end;
  n.points.push_back({start.x, start.y, 1});
  if (code == 51) {
    if (!b_->has('i') || !b_->has('j'))
      fail(b_->has('i')   ? column_of('i')
           : b_->has('j') ? column_of('j')
                          : column,
           "G5.1 needs both I and J");
    n.order = 3;
    n.points.push_back({start.x + b_->value('i'), start.y + b_->value('j'), 1});
  } else {
    double i = s_.cycle.ijk[0], j = s_.cycle.ijk[1];  // the last G5's end direction
    if (b_->has('i') != b_->has('j'))
      fail(column_of(b_->has('i') ? 'i' : 'j'), "G5 needs both I and J, or neither");
    if (b_->has('i')) {
      i = b_->value('i');
      j = b_->value('j');
    }
    if (!b_->has('p') || !b_->has('q'))
      fail(b_->has('p')   ? column_of('p')
           : b_->has('q') ? column_of('q')
                          : column,
           "G5 needs both P and Q");
    n.order = 4;
    n.points.push_back({start.x + i, start.y + j, 1});
    n.points.push_back({end.x + b_->value('p'), end.y + b_->value('q'), 1});
    // rs274 keeps them where G87 keeps its I J.
    s_.cycle.ijk[0] = -b_->value('p');
    s_.cycle.ijk[1] = -b_->value('q');
  }
  n.points.push_back({end.x, end.y, 1});
  // No SET_FEED_RATE in G93: rs274 makes none for a spline.
  const double f = s_.feed_mode == FeedMode::kInverseTime ? b_->value('f') : 0;
  out_.emit(std::move(n), f);
  last_program_position_ = end;
  s_.position_mm = target;
}

void BlockExecutor::nurbs_point(const Axes6& target, int column, bool axis_words) {
  NurbsRun& run = s_.nurbs;
  // rs274 does not take polar words as X and Y here (its checks then
  // refuse a later control point, and drop the motion of a first one).
  if (b_->has_polar())
    fail(b_->polar_column(), "G5.2 control points take X and Y, not polar words (@ ^)");
  const bool x = b_->has('x'), y = b_->has('y');
  if (x != y) fail(column_of(x ? 'x' : 'y'), "G5.2 control points need both X and Y");
  const bool point = x && y;
  const bool has_p = b_->has('p');
  const double p = has_p ? b_->value('p') : -1;  // rs274's P when absent
  if (!point && p > 0 && !run.points.empty())
    fail(column_of('p'), "G5.2: P without X and Y only on the first control point");
  if (p <= 0 && !run.points.empty())
    fail(has_p ? column_of('p') : column, "G5.2: every control point needs a positive weight P");
  if (s_.feed_mode == FeedMode::kUnitsPerMinute && s_.feed <= 0)
    fail(column, "G5.2 NURBS with a zero feed rate: program F first");
  // rs274 runs these; truecut refuses rather than move differently.
  if (s_.comp.side != 0)
    fail(column,
         "G5.2 NURBS with cutter radius compensation on is not supported (G40 first; rs274 "
         "mixes the NURBS into its compensated moves)");
  for (char l : kOffAxisLetters)
    if (b_->has(l))
      fail(column_of(l),
           "G5.2 control points take X Y only (rs274 ignores Z, A, B, C there: the axis would not "
           "move)");
  if (point && p <= 0)
    fail(has_p ? column_of('p') : column,
         "G5.2: the first control point needs a positive weight P too (rs274 takes -1)");
  (void)axis_words;
  if (run.points.empty()) {
    const Axes6 start = s_.program_position(move_base());
    run.points.push_back({start.x, start.y, !point && p > 0 ? p : 1.0});
    run.order = 3;
    run.line = s_.line;
  }
  if (b_->has('l')) {
    const double l = b_->value('l');
    if (l != std::floor(l) || l > kLargestWholeWord)
      fail(column_of('l'), "G5.2 order L must be a whole number");
    if (l > 3) run.order = static_cast<int>(l);  // rs274 ignores L up to 3
  }
  if (point) {
    const Axes6 at = s_.program_position(target);
    run.points.push_back({at.x, at.y, p});
  }
}

void BlockExecutor::nurbs_end(int column, bool axis_words) {
  NurbsRun& run = s_.nurbs;
  if (run.points.empty()) fail(column, "G5.3 without G5.2 first");
  if (axis_words) fail(column, "G5.3 takes no axis words");
  if (run.points.size() < static_cast<size_t>(run.order))
    fail(column, "the G5.2 NURBS needs at least as many control points as its order L = " +
                     std::to_string(run.order) + " (it has " + std::to_string(run.points.size()) +
                     ", with its start)");
  NurbsFeed n;
  n.points = std::move(run.points);
  n.order = run.order;
  Axes6 end = s_.program_position();
  end.x = n.points.back().x;
  end.y = n.points.back().y;
  n.end = end;
  const double f = s_.feed_mode == FeedMode::kInverseTime && b_->has('f') ? b_->value('f') : 0;
  out_.emit(std::move(n), f);
  run = NurbsRun{};
  last_program_position_ = end;
  s_.position_mm = s_.machine_position(end);
  s_.motion = kMotionNone;
}

}  // namespace truecut::interp
