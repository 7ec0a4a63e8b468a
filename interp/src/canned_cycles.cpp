// The canned cycles G73, G74, G81-G89 as LinuxCNC 2.9's interpreter runs
// them (docs/gcode.md, "Canned cycles"): each block expands into rapids,
// feeds, dwells and spindle calls in the selected plane.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <string>

#include "block_executor.hpp"
#include "truecut/interp/path_geometry.hpp"

namespace truecut::interp {

namespace {

constexpr char kLetters[6] = {'x', 'y', 'z', 'a', 'b', 'c'};
// At most this many holes (L) and pecks × holes in one cycle block: no
// legitimate program comes near, a mistyped L or Q does.
constexpr double kMaxCycleMoves = 1e7;

std::string upper(char c) {
  return std::string(1, static_cast<char>(std::toupper(static_cast<unsigned char>(c))));
}

// The current position comes back from machine millimetres (offsets, inch):
// equal heights can differ in the last bits, where rs274 keeps the program
// numbers exactly. Heights this close count as equal.
bool same_height(double a, double b) {
  return std::abs(a - b) <= 1e-9 * std::max({1.0, std::abs(a), std::abs(b)});
}

std::string number(double v) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

}  // namespace

void BlockExecutor::canned_cycle(int code, int column) {
  const std::string name = "G" + std::to_string(code / 10);
  if (s_.feed_mode == FeedMode::kInverseTime)
    fail(column, "canned cycle " + name + " with inverse-time feed (G93): program G94");
  if (s_.feed <= 0)
    fail(column,
         "canned cycle " + name + " with a zero feed rate: program F before or on this line");
  for (char l : {'a', 'b', 'c'})
    if (b_->has(l))
      fail(column_of(l),
           upper(l) + " word in canned cycle " + name + ": rotary axes do not move in a cycle");

  // The plane's first and second axes locate the hole; the normal axis
  // (Z in G17, Y in G18, X in G19) drills it.
  const path_geometry::PlaneAxes ax = path_geometry::plane_axes(s_.plane);
  const int ia = ax.first, ib = ax.second, ic = ax.normal;
  const char la = kLetters[ia], lb = kLetters[ib], lc = kLetters[ic];
  // Polar words (@ ^) locate the hole in X Y: only when those are the
  // plane's first axes (rs274 would mix them with the drilling axis).
  if (b_->has_polar() && s_.plane != Plane::kXY)
    fail(b_->polar_column(),
         "polar coordinates (@ ^) in canned cycle " + name + " outside the XY plane (G17)");
  CycleState& cy = s_.cycle;
  // R, the normal-axis word, P and Q carry over from the previous block
  // only while the same cycle continues.
  const bool same = cy.last_code == code;

  double r_word = cy.r;
  if (b_->has('r'))
    r_word = b_->value('r');
  else if (!same)
    fail(column, name + " needs R (the retract plane) on its first block");
  int repeats = 1;
  if (b_->has('l')) {
    const double l = b_->value('l');
    if (l < 1 || l != std::floor(l))
      fail(column_of('l'), "L (repeats of the canned cycle) must be a whole number >= 1");
    if (l > kMaxCycleMoves)
      fail(column_of('l'), "L " + number(l) + ": more than " + number(kMaxCycleMoves) +
                               " repeats of a canned cycle on one line (the cycle budget)");
    repeats = static_cast<int>(l);
  }
  double bottom_word = cy.bottom;
  if (b_->has(lc))
    bottom_word = b_->value(lc);
  else if (!same)
    fail(column, name + " needs " + upper(lc) + " (the hole bottom) on its first block");

  const bool dwells = code == 820 || code == 860 || code == 880 || code == 890;
  // The tapping cycles dwell at the bottom for P, or the last cycle's P
  // (any cycle's, 0 at first), as rs274 does.
  const bool taps = code == 740 || code == 840;
  const bool pecks = code == 730 || code == 830;
  double dwell = cy.p, peck = cy.q;
  if (dwells || taps) {
    if (b_->has('p'))
      dwell = b_->value('p');
    else if (!same && dwells)
      fail(column, name + " needs P (the dwell in seconds)");
    if (dwell < 0)
      fail(b_->has('p') ? column_of('p') : column, "dwell time P must not be negative");
  }
  if (pecks) {
    if (b_->has('q'))
      peck = b_->value('q');
    else if (!same)
      fail(column, name + " needs Q (the peck depth)");
    if (peck <= 0)
      fail(b_->has('q') ? column_of('q') : column, "Q (the peck depth) must be greater than zero");
  }
  if ((code == 860 || code == 870 || code == 880 || taps) && s_.spindle == 0)
    fail(column, name + " needs the spindle turning (" +
                     (code == 740   ? "M4"
                      : code == 840 ? "M3"
                                    : "M3 or M4") +
                     ")");
  // rs274 2.9 feeds a G18/G19 tap to a point with its axes mixed up (it
  // passes the hole's coordinates to the feed in the wrong order): refused
  // rather than copied.
  if (taps && s_.plane != Plane::kXY)
    fail(column, name +
                     " (tapping) outside the XY plane (G17): LinuxCNC 2.9 feeds it to the "
                     "wrong point in G18 and G19");
  if (code == 740 && s_.spindle > 0)
    fail(column, "G74 (left-hand tapping) with the spindle turning clockwise: program M4");
  if (code == 840 && s_.spindle < 0)
    fail(column, "G84 (right-hand tapping) with the spindle turning counterclockwise: program M3");
  // G87: the offset of the entry point along the plane's axes (I J K of
  // those axes, always incremental) and the top of the back bore (the
  // normal axis' letter: K in G17).
  double ijk[3] = {cy.ijk[0], cy.ijk[1], cy.ijk[2]};
  if (code == 870)
    for (int i = 0; i < 3; ++i) {
      const char l = static_cast<char>('i' + i);
      if (b_->has(l))
        ijk[i] = b_->value(l);
      else if (!same)
        fail(column, "G87 needs " + upper(l) + " on its first block");
    }

  Axes6 at = s_.program_position();
  // The initial level: where the normal axis was when this run of cycles
  // began (G98 returns there).
  if (!cy.level_set) {
    cy.level = at[ic];
    cy.level_set = true;
  }
  double level = cy.level;
  double a = at[ia], b = at[ib], a_step = 0, b_step = 0, r = 0, bottom = 0;
  if (s_.incremental) {
    // X, Y (in-plane) step from the current point; R from the initial
    // level; the hole bottom from R.
    if (b_->has(la)) a_step = b_->value(la);
    if (b_->has(lb)) b_step = b_->value(lb);
    r = r_word + level;
    bottom = r + bottom_word;
  } else {
    if (b_->has(la)) a = b_->value(la);
    if (b_->has(lb)) b = b_->value(lb);
    r = r_word;
    bottom = bottom_word;
  }
  // G87's back-bore top: absolute in G90, from the bottom in G91.
  const double middle = s_.incremental ? bottom + ijk[ic] : ijk[ic];
  if (r < bottom)
    fail(b_->has('r') ? column_of('r') : column,
         "R (the retract plane, " + number(r) + ") is below the hole bottom " + upper(lc) + " (" +
             number(bottom) + ") in canned cycle " + name);
  if (pecks) {
    // Pecks per hole times holes: a tiny Q or a huge L must not run away.
    const double per_hole = std::ceil((r - bottom) / peck) + 4.0;
    if (!(per_hole * repeats <= kMaxCycleMoves))
      fail(b_->has('q') ? column_of('q') : column,
           "Q " + number(peck) + " makes more than " + number(kMaxCycleMoves) +
               " moves of canned cycle " + name + " on one line (the cycle budget)");
  }

  auto move = [&](bool rapid, double pa, double pb, double pc) {
    at[ia] = pa;
    at[ib] = pb;
    at[ic] = pc;
    Axes6 target = s_.position_mm;
    const Axes6 m = s_.machine_position(at);
    for (int i = 0; i < 3; ++i)
      target[i] = m[i];
    straight(rapid, target, 0);
  };

  // Below the R plane: straight up to it first.
  if (level < r && !same_height(level, r)) {
    move(true, at[ia], at[ib], r);
    level = r;
  }
  const double clear = s_.retract_old_z ? level : r;
  const bool exact = s_.path == PathMode::kExactPath;
  if (!exact) out_.emit(SetMotionControlMode{PathMode::kExactPath, 0});
  // The chip-breaking back-off of G73 and the approach gap of G83: 0.010 in.
  const double backoff = s_.units == LengthUnits::kMm ? 0.010 * kMmPerInch : 0.010;

  // G90: the polar point is computed once from where the block starts.
  if (b_->has_polar() && !s_.incremental) polar_point(a, b);
  for (int rep = 0; rep < repeats; ++rep) {
    a += a_step;
    b += b_step;
    // G91: like rs274, each repeat adds @ and ^ to the last hole's radius
    // and angle.
    if (b_->has_polar() && s_.incremental) polar_point(a, b);
    // Over the hole at the current height or the clearance height,
    // whichever is higher, then down to R.
    const double over = at[ic] > clear && !same_height(at[ic], clear) ? at[ic] : clear;
    move(true, a, b, over);
    if (!same_height(over, r)) move(true, a, b, r);
    switch (code) {
      case 810:
        move(false, a, b, bottom);
        move(true, a, b, clear);
        break;
      case 820:
        move(false, a, b, bottom);
        out_.emit(Dwell{dwell});
        move(true, a, b, clear);
        break;
      case 730:
      case 830:
        for (double depth = r - peck; depth > bottom; depth -= peck) {
          move(false, a, b, depth);
          if (code == 830) move(true, a, b, r);
          move(true, a, b, depth + backoff);
        }
        move(false, a, b, bottom);
        move(true, a, b, clear);
        break;
      case 850:
        move(false, a, b, bottom);
        move(false, a, b, r);
        move(true, a, b, clear);
        break;
      case 860:
        move(false, a, b, bottom);
        out_.emit(Dwell{dwell});
        out_.emit(StopSpindle{});
        move(true, a, b, clear);
        out_.emit(StartSpindle{s_.spindle > 0});
        break;
      case 880:
        // The operator retracts by hand; the interpreter carries on as if
        // the tool were at the clearance height.
        move(false, a, b, bottom);
        out_.emit(Dwell{dwell});
        out_.emit(StopSpindle{});
        out_.emit(ProgramStop{false});
        out_.emit(StartSpindle{s_.spindle > 0});
        at[ic] = clear;
        s_.position_mm[ic] = s_.machine_position(at)[ic];
        break;
      case 890:
        move(false, a, b, bottom);
        out_.emit(Dwell{dwell});
        move(false, a, b, clear);
        break;
      case 740:
      case 840: {
        // Overrides off, feed in, reverse, dwell, feed out, restore.
        const bool right_hand = code == 840;
        out_.emit(FeedOverride{false});
        out_.emit(SpeedOverride{false});
        move(false, a, b, bottom);
        out_.emit(StopSpindle{});
        out_.emit(StartSpindle{!right_hand});
        out_.emit(Dwell{dwell});
        move(false, a, b, clear);
        out_.emit(StopSpindle{});
        out_.emit(StartSpindle{right_hand});
        out_.emit(FeedOverride{true});
        out_.emit(SpeedOverride{true});
        break;
      }
      case 870: {
        // Oriented through the hole at the offset point, back bore upward
        // from the bottom to `middle` and down again, out the same way.
        const bool cw = s_.spindle > 0;
        const double oa = a + ijk[ia], ob = b + ijk[ib];
        move(true, oa, ob, r);
        out_.emit(StopSpindle{});
        out_.emit(OrientSpindle{0, cw});
        move(true, oa, ob, bottom);
        move(true, a, b, bottom);
        out_.emit(StartSpindle{cw});
        move(false, a, b, middle);
        move(false, a, b, bottom);
        out_.emit(StopSpindle{});
        out_.emit(OrientSpindle{0, cw});
        move(true, oa, ob, bottom);
        move(true, oa, ob, clear);
        move(true, a, b, clear);
        out_.emit(StartSpindle{cw});
        break;
      }
      default:
        break;
    }
  }
  if (!exact) {
    out_.emit(SetMotionControlMode{s_.path, s_.blend_tolerance});
    out_.emit(SetNaivecamTolerance{s_.naive_tolerance});
  }
  cy.last_code = code;
  cy.r = r_word;
  cy.bottom = bottom_word;
  if (dwells || taps) cy.p = dwell;
  if (code == 870) std::copy(ijk, ijk + 3, cy.ijk);
  if (pecks) cy.q = peck;
}

}  // namespace truecut::interp
