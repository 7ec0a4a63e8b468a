// A cubic span as a path piece with an approximate arc-length parameter.
#pragma once

#include "truecut/interp/plan_segment.hpp"
#include "truecut/interp/spline.hpp"

namespace truecut::interp::plan {

// False for a span of (near) zero length.
bool cubic_piece(const CubicSpan& span, PathPiece& piece);

}  // namespace truecut::interp::plan
