#include "truecut/sim/cutting/swept_cut.hpp"

#include <algorithm>

namespace truecut::sim::cutting {

namespace {

bool same(const CutterShape& a, const CutterShape& b) {
  return a.radius_mm == b.radius_mm && a.corner_radius_mm == b.corner_radius_mm &&
         a.flute_length_mm == b.flute_length_mm;
}

bool same(const CutterPose& a, const CutterPose& b) {
  return a.tip_mm == b.tip_mm && a.axis == b.axis;
}

}  // namespace

Engagement SweptCut::cut_to(DexelModel& model, const CutterShape& shape, const CutterPose& to,
                            std::uint64_t to_cycle) noexcept {
  const Engagement e = model.cut(shape, cut_, to, false);
  covered_ = static_cast<int>(std::clamp<std::uint64_t>(to_cycle - cut_cycle_, 1, 1u << 30));
  cut_ = to;
  cut_cycle_ = to_cycle;
  return e;
}

Engagement SweptCut::step(DexelModel& model, const CutterShape& shape,
                          const CutterPose& pose) noexcept {
  ++cycle_;
  if (!valid(shape) || !valid(pose)) {
    Engagement e = finish(model);
    e.invalid_input = true;
    return e;
  }
  if (!started_) {
    const Engagement e = model.cut(shape, pose, pose, false);  // the instance at `pose`
    shape_ = shape;
    cut_ = last_ = pose;
    cut_cycle_ = cycle_;
    covered_ = 1;
    started_ = true;
    pending_ = false;
    return e;
  }
  if (!same(shape, shape_)) {
    const Engagement e = cut_to(model, shape, pose, cycle_);
    shape_ = shape;
    last_ = pose;
    pending_ = false;
    return e;
  }
  if (model.substeps_needed(shape, cut_, pose) <= 1) {
    last_ = pose;
    pending_ = !same(pose, cut_);
    return {};
  }
  if (pending_) {
    // One cycle late: the instance at the last pose that needed none between.
    const Engagement e = cut_to(model, shape, last_, cycle_ - 1);
    last_ = pose;
    pending_ = true;
    return e;
  }
  const Engagement e = cut_to(model, shape, pose, cycle_);
  last_ = pose;
  return e;
}

Engagement SweptCut::finish(DexelModel& model) noexcept {
  Engagement e;
  if (started_ && pending_) e = cut_to(model, shape_, last_, cycle_);
  started_ = false;
  pending_ = false;
  return e;
}

Engagement CycleCut::step(DexelModel& model, const CutterShape& shape,
                          const CutterPose& pose) noexcept {
  const Engagement e = model.cut(shape, started_ ? previous_ : pose, pose, !started_);
  started_ = !e.invalid_input;
  if (started_) previous_ = pose;
  return e;
}

}  // namespace truecut::sim::cutting
