// Centre and turn count of G2/G3 arcs from the R or I/J/K form, with
// LinuxCNC's checks. Works in the two coordinates of the active plane,
// ordered as LinuxCNC's canonical ARC_FEED orders them (XY: x,y; XZ: z,x;
// YZ: y,z), in program units.
#pragma once

#include <stdexcept>
#include <string>

namespace truecut::interp {

struct ArcRequest {
  bool clockwise = false;
  double start[2] = {0, 0};
  double end[2] = {0, 0};
  bool radius_form = false;
  double radius = 0;             // R (negative: more than half a turn)
  double center_in[2] = {0, 0};  // I/J/K, incremental or absolute (G90.1)
  bool absolute_center = false;
  int turns = 1;      // P
  bool inch = false;  // tolerances follow the units
};

struct ArcResult {
  double center[2] = {0, 0};
  int rotation = 1;  // signed turns: negative clockwise
};

// What went wrong and which word to point at ('r', 'i', or 0 for the code).
struct ArcDataError : std::runtime_error {
  ArcDataError(const std::string& message, char word_to_point_at)
      : std::runtime_error(message), word(word_to_point_at) {}
  char word = 0;
};

ArcResult compute_arc(const ArcRequest& request);  // throws ArcDataError

// Length of the (helical) path, for inverse-time feed.
double arc_length(const ArcRequest& request, const ArcResult& arc, double axis_travel);

}  // namespace truecut::interp
