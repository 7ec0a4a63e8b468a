// Material removal sampled by the distance the tool sweeps, not by the servo
// cycle: at a few µm of feed per cycle most cycles move the tool so little
// that the instance at the cycle's end adds nothing the tolerance needs. The
// sampler places a tool instance only where DexelModel::cut() would need one
// (DexelModel::substeps_needed > 1 from the last instance), always at a pose
// the tool really had, so the surface keeps the tolerance of a cut per cycle
// (docs/cutting.md, "Sampling the sweep").
//
//   SweptCut sampler;
//   each cycle:  Engagement e = sampler.step(model, shape, pose);  // no allocation
//   tool lifted: Engagement e = sampler.finish(model);             // the pending motion
#pragma once

#include <cstdint>

#include "truecut/sim/cutting/cutter.hpp"
#include "truecut/sim/cutting/dexel_model.hpp"

namespace truecut::sim::cutting {

class SweptCut {
 public:
  // The tool is at `pose` this cycle. Cuts up to the last pose from which the
  // sweep still needs no instance in between, or nothing (the motion waits
  // for the next call). The first call after construction or finish() cuts
  // the instance at `pose`. A changed shape cuts at once (to `pose`, with the
  // new shape, as a cut per cycle does). An invalid shape or pose cuts the
  // pending motion with the last valid shape and returns invalid_input; the
  // next valid call starts afresh. Allocates nothing, throws nothing.
  Engagement step(DexelModel& model, const CutterShape& shape, const CutterPose& pose) noexcept;
  // Cuts the motion still pending (none after a cut) and starts afresh.
  Engagement finish(DexelModel& model) noexcept;
  bool pending() const noexcept { return pending_; }
  // The number of cycles (step() calls) whose motion the latest cut covered:
  // its removal belongs to that many cycles, not to the one it was cut in.
  int cycles_covered() const noexcept { return covered_; }

 private:
  Engagement cut_to(DexelModel& model, const CutterShape& shape, const CutterPose& to,
                    std::uint64_t to_cycle) noexcept;

  CutterShape shape_;
  CutterPose cut_;               // where the last instance was placed
  CutterPose last_;              // the latest pose, not yet cut when pending_
  std::uint64_t cycle_ = 0;      // step() calls so far
  std::uint64_t cut_cycle_ = 0;  // the call whose pose cut_ is
  int covered_ = 1;
  bool started_ = false;
  bool pending_ = false;
};

// Every cycle cut from the previous cycle's pose (the sampling before
// SweptCut; `sampling=cycle` of the cutting component).
class CycleCut {
 public:
  Engagement step(DexelModel& model, const CutterShape& shape, const CutterPose& pose) noexcept;
  Engagement finish(DexelModel&) noexcept {
    started_ = false;
    return {};
  }
  int cycles_covered() const noexcept { return 1; }

 private:
  CutterPose previous_;
  bool started_ = false;
};

}  // namespace truecut::sim::cutting
