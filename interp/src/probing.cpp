// Probing G38.2-G38.5 as LinuxCNC 2.9's interpreter makes it (docs/gcode.md,
// "Probing"): TURN_PROBE_ON, STRAIGHT_PROBE, TURN_PROBE_OFF; then the
// parameters #5061-#5070 and the position from what the probe reported.
#include <algorithm>
#include <cmath>
#include <string>

#include "block_executor.hpp"

namespace truecut::interp {

namespace {

// The first parameter of the probe result (#5061 X ... #5069 W, #5070 trip).
constexpr int kProbeParameter = 5061;

}  // namespace

ProbeResult standalone_probe(const ProbeRequest& request) {
  ProbeResult r;
  r.tripped = false;
  r.trip_mm = request.target_mm;
  r.end_mm = request.target_mm;
  double d[3], distance = 0;
  for (int i = 0; i < 3; ++i) {
    d[i] = request.start_mm[i] - request.target_mm[i];
    distance += d[i] * d[i];
  }
  distance = std::sqrt(distance);
  // rs274's stand-in canon layer backs off 0.01 in (0.254 mm) toward the
  // start, as a machine would after the probe tripped.
  constexpr double kBackoffMm = 0.254;
  if (distance > 0)
    for (int i = 0; i < 3; ++i)
      r.end_mm[i] += kBackoffMm * d[i] / distance;
  return r;
}

void BlockExecutor::probe(int code, const Axes6& target, int column, bool axis_words) {
  const int kind = code - 380;
  const std::string name = "G38." + std::to_string(kind);
  if (!axis_words) fail(column, name + " needs an axis word (where to probe)");
  if (s_.comp.side != 0)
    fail(column, "cannot probe (" + name + ") with cutter radius compensation on (G40 first)");
  if (s_.feed_mode == FeedMode::kInverseTime)
    fail(column, name + " with inverse-time feed (G93): program G94 and F");
  if (s_.feed_mode == FeedMode::kUnitsPerRevolution)
    fail(column, "cannot probe (" + name + ") with feed per revolution (G95): program G94 and F");
  if (s_.feed <= 0) fail(column, name + " with a zero feed rate: program F before or on this line");
  bool moves = false;
  for (int i = 0; i < 6; ++i)
    if (std::abs(target[i] - s_.position_mm[i]) > 1e-12 * std::max(1.0, std::abs(target[i])))
      moves = true;
  // As rs274: only the probes that must trip refuse to start at the target.
  if (!moves && (kind == 2 || kind == 4))
    fail(column, name + ": the start point is the probe point (nothing to probe)");

  const ProbeRequest request{s_.position_mm, target, kind};
  const ProbeResult r = probe_ != nullptr ? (*probe_)(request) : standalone_probe(request);
  out_.emit(ProbeSwitch{true});
  out_.emit(StraightProbe{s_.program_position(target), kind, s_.program_position(r.trip_mm),
                          s_.program_position(r.end_mm)});
  out_.emit(ProbeSwitch{false});

  // A probe toward the work that does not trip is an error on LinuxCNC
  // (G38.2, G38.4); G38.3 and G38.5 carry on. The stand-in never errs, as
  // rs274 alone does not.
  if (probe_ != nullptr && !r.tripped && (kind == 2 || kind == 4))
    fail(column, name + ": the probe move ended without the probe " +
                     (kind == 2 ? "tripping" : "losing contact"));
  // #5061-#5069: the trip point in the active coordinate system and
  // program units (X Y Z A B C U V W); #5070: 1 when it tripped.
  const Axes6 trip = s_.program_position(r.trip_mm);
  for (int i = 0; i < 6; ++i)
    params_.set(kProbeParameter + i, trip[i]);
  for (int i = 6; i < 9; ++i)
    params_.set(kProbeParameter + i, 0);
  params_.set(kProbeParameter + 9, r.tripped ? 1 : 0);
  // The machine is where the probe stopped.
  s_.position_mm = r.end_mm;
  last_program_position_ = s_.program_position(r.end_mm);
}

}  // namespace truecut::interp
