// One piece of a time-parametrised plan, as the non-real-time planner hands
// it to the per-cycle interpolator through a lock-free channel. Everything
// is inline and trivially copyable: a segment carries its geometry, its time
// law and what the cycle must report while it runs.
//
// Geometry lives in the 5-D planning space (x, y, z, w*a, w*c): joint space
// for ordinary programs, (TCP, rotary angles) in TCP mode (TRAORI), where w
// is PlanSegment::rotary_weight_mm_per_deg.
#pragma once

#include <array>
#include <cstdint>

#include "truecut/rt/core/kinematics_ac.hpp"

namespace truecut::interp {

using Vec5 = std::array<double, 5>;

// A curve P(u), u in [0, length] (planning-space arc length for lines and
// arcs, close to it for cubic spans).
struct PathPiece {
  enum Kind : std::uint8_t { kLine, kArc, kCubic };
  Kind kind = kLine;
  double length = 0;
  // kLine: start + u * dir (dir unit).
  // kArc: centre + r(θ)(cos θ e1 + sin θ e2) + θ * drift, θ = sweep * u / length,
  //       r(θ) = radius + (radius_end - radius) θ / sweep (a spiral when the
  //       programmed end radius differs slightly).
  // kCubic: c0 + c1 t + c2 t^2 + c3 t^3, t = m1 u + ... + m5 u^5: an
  //       approximate arc-length map that matches the true one to second
  //       order at both ends, so joined spans keep a continuous acceleration.
  Vec5 a{}, b{}, c{}, d{};  // line: a = start, b = dir; arc: a = centre, b = e1, c = e2, d = drift
                            // cubic: a..d = c0..c3
  double radius = 0, radius_end = 0, sweep_rad = 0;
  double m1 = 0, m2 = 0, m3 = 0, m4 = 0, m5 = 0;
};

Vec5 evaluate(const PathPiece& piece, double u) noexcept;
// The point at u + du, with du's share of an arc's angle kept apart from u's:
// u + du keeps 16 digits, so far along an arc of many turns (u of 6e8 mm,
// last digit 1e-7 mm) differences over a small du would read its rounding.
Vec5 evaluate_near(const PathPiece& piece, double u, double du) noexcept;

// A jerk-limited (S-curve) law s(t) in at most 7 phases of constant jerk.
struct TimeLaw {
  struct Phase {
    double duration_s = 0, s0 = 0, v0 = 0, a0 = 0, jerk = 0;
  };
  std::array<Phase, 7> phase{};
  int phases = 0;
  double duration_s = 0;
  double length = 0;
};

struct LawState {
  double s = 0, v = 0, a = 0, jerk = 0;
};
LawState evaluate(const TimeLaw& law, double t_s) noexcept;

enum class SegmentKind : std::uint8_t { kMotion, kDwell };

struct PlanSegment {
  SegmentKind kind = SegmentKind::kMotion;
  bool tcp = false;   // planning space is (TCP, A, C), joints from inverse_ac
  bool last = false;  // the program ends with this segment
  bool rapid = false;
  PathPiece piece;
  double u0 = 0;  // the segment runs u0 .. u0 + law.length along the piece
  TimeLaw law;
  double rotary_weight_mm_per_deg = 1.0;
  rt::AcTrtParams kinematics;  // tool_length_mm already includes the tool in use
  std::int32_t line = 0;       // program line (main file or subroutine file)
  std::int32_t tool = 0;
  std::int32_t operation = 0;  // 1-based index into Plan::operations, 0 = none
  double programmed_feed_mm_per_s = 0;
  double spindle_rpm = 0;  // commanded spindle speed, 0 while stopped
};

}  // namespace truecut::interp
