// The planner's intermediate form: the program as a list of geometric moves
// in the planning space, each with its feed, path-control mode and what the
// servo cycle must report while it runs.
#pragma once

#include <string>
#include <vector>

#include "truecut/interp/canon.hpp"
#include "truecut/interp/planner.hpp"

namespace truecut::interp::plan {

enum class FeedMetric { kXyz, kRotary };

struct Move {
  PathPiece piece;
  bool dwell = false;
  double dwell_s = 0;
  bool tcp = false;
  bool rapid = false;
  bool spline = false;  // a span of a BSPLINE/CSPLINE curve
  FeedMetric metric = FeedMetric::kXyz;
  double feed = 0;  // in the metric's units per second (mm/s or deg/s)
  // A blend also obeys the feed of the move it leads into.
  FeedMetric blend_metric_out = FeedMetric::kXyz;
  double blend_feed_out = 0;  // 0: not a blend
  // How the junction at the end of this move is passed.
  PathMode mode = PathMode::kContinuous;
  double tolerance_mm = 0;  // G64 P, 0 = none given
  bool stop_after = false;  // tool change, program stop, mode switch, end
  rt::AcTrtParams kinematics;
  int line = 0, tool = 0, operation = 0;
  double programmed_feed_mm_per_s = 0;
  double spindle_rpm = 0;  // 0 while the spindle is stopped
};

struct Path {
  std::vector<Move> moves;
  std::vector<std::string> operations;
  std::vector<SplineReport> splines;
  int programmed_moves = 0;
};

Path build_path(const CanonProgram& program, const PlannerOptions& options);

// Replaces corners between lines under G64 by tangent arcs; returns how many.
int insert_blends(std::vector<Move>& moves, const PlannerOptions& options);

double norm(const Vec5& v);
Vec5 sub(const Vec5& a, const Vec5& b);

}  // namespace truecut::interp::plan
