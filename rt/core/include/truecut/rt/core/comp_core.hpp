// The servo-cycle logic of truecut_comp, free of the HAL: one call per cycle
// takes the inputs and the state, returns the correction. Called in this
// order inside step():
//   0. a rising reset clears the fault latch
//   1. check the tunables (an invalid one: the last valid value, and a fault
//      that fades the correction to zero)
//   2. switch source (new field, new tool) if no cross-fade is running
//   3. evaluate the current and the outgoing source at the TCP
//   4. fault handling: a failing source holds its last good correction
//   5. advance the fades, cross-fade
//   6. clamp the magnitude, then limit the velocity, acceleration and jerk,
//      then the hard bound
// Real-time safe: noexcept, no allocation, at most two field evaluations.
#pragma once

// Part of the real-time core: include "truecut/rt/comp.hpp" (std and Eigen only).

#include <cstdint>

#include "truecut/rt/core/comp_math.hpp"
#include "truecut/rt/core/correction_field.hpp"

namespace truecut::rt::comp {

// The `fault` pin. When several apply, the lowest-numbered wins except that
// input and parameter faults are reported before field faults.
enum class Fault : int32_t {
  kNone = 0,
  kNoField = 1,         // no field loaded
  kNoLayer = 2,         // the field has no layer for the tool
  kOutsideGrid = 3,     // the TCP is outside the field's grid
  kInputNotFinite = 4,  // NaN/Inf on a position or axis input
  kFieldNotFinite = 5,  // the field evaluated to NaN/Inf
  kBadParameter = 6,    // a limit NaN/Inf or < 0, or max-rate 0: the last valid one is used
  kKinematics = 7,      // joint mode: joint A outside [a-min, a-max]
  kBoundStep = 8,       // max-correction (or max-tilt) was lowered below the output
                        // by more than the limits let it follow: the output stepped
  kBoundClip = 9,       // the output reached max-correction (or max-tilt) faster
                        // than the limits let it stop there: clipped, a limit exceeded
  kWrongField = 10,     // the field names another machine, part or tool set
                        // than the expected ids: not applied
  kJointLimit = 11,     // joint mode: the correction would have pushed a linear
                        // joint past its soft limit or its own max-correction:
                        // clipped there, reported (does not latch)
};

inline const char* to_string(Fault f) noexcept {
  switch (f) {
    case Fault::kNone:
      return "none";
    case Fault::kNoField:
      return "no-field";
    case Fault::kNoLayer:
      return "no-layer";
    case Fault::kOutsideGrid:
      return "outside-grid";
    case Fault::kInputNotFinite:
      return "input-not-finite";
    case Fault::kFieldNotFinite:
      return "field-not-finite";
    case Fault::kBadParameter:
      return "bad-parameter";
    case Fault::kKinematics:
      return "kinematics";
    case Fault::kBoundStep:
      return "bound-step";
    case Fault::kBoundClip:
      return "bound-clip";
    case Fault::kWrongField:
      return "wrong-field";
    case Fault::kJointLimit:
      return "joint-limit";
  }
  return "unknown";
}

// A correction: the translation of the tool-centre point (mm) and the
// rotation of the tool about it (rad, a rotation vector; zero unless the
// field has a rotation). Both in the workpiece frame.
struct Correction {
  Vec3 translation_mm = Vec3::Zero();
  Vec3 rotation_rad = Vec3::Zero();
};

// One source of correction: a field layer, faded in by u.
struct Channel {
  const rt::CorrectionField* field = nullptr;
  int32_t tool = 0;
  Correction held;      // last good (weighted) correction of this source
  double u = 0.0;       // fade progress in [0, 1]
  bool frozen = false;  // failed: outputs `held` until faded out or replaced
};

// The motion of one shaped output (the translation, mm, or the rotation,
// rad; "unit" below): where it is, how it moves, what it followed.
struct Shaped {
  Vec3 output = Vec3::Zero();        // output by the last cycle, unit
  Vec3 velocity = Vec3::Zero();      // of the output, unit/s
  Vec3 accel = Vec3::Zero();         // of the output, unit/s^2
  Vec3 target_prev = Vec3::Zero();   // last cycle's wanted (clamped) value
  Vec3 target_prev2 = Vec3::Zero();  // the cycle's before
  double bound_prev = 0.0;           // last cycle's bound
  int32_t clip_cycles = 0;           // cycles still affected by the last bound-clip (reported)
  int32_t joint_clip_cycles = 0;     // cycles still showing the last joint clip (reported)
  // Output, velocity, acceleration and the last targets are all exactly
  // zero: at rest at zero, nothing to shape while the wanted value is zero.
  bool resting = true;
};

struct CompState {
  Channel current;   // the source being faded in (or held)
  Channel outgoing;  // the source being faded out; idle when u == 0
  Shaped translation{.bound_prev = kDefaultMaxCorrectionMm};  // mm
  Shaped rotation{.bound_prev = kDefaultMaxTiltRad};          // rad
  // The last valid value of each tunable (kBadParameter: the invalid one is
  // replaced by it, and the correction fades to zero at these limits).
  CompLimits last_good;
  int32_t clamp_count = 0;       // cycles in which max-correction or max-tilt acted (wraps)
  Fault latched = Fault::kNone;  // a latching fault, held until a rising `reset`
  bool reset_prev = false;
  int32_t joint_clip_count = 0;  // cycles clipped by a joint's limits (wraps)
};

// Joint mode: the box the correction of the linear joints X Y Z must stay in
// this cycle (from their soft limits and per-joint maximum corrections,
// joint_clip() in joint_mode.hpp). The correction d in joint space is
// to_workpiece^T c (the table rotation is orthonormal); it is clipped to
// [lo, hi] (lo <= 0 <= hi) and mapped back.
struct JointClip {
  bool active = false;
  Eigen::Matrix3d to_workpiece = Eigen::Matrix3d::Identity();  // column k: TCP per mm of joint k
  Vec3 lo = Vec3::Zero();                                      // mm
  Vec3 hi = Vec3::Zero();
};

struct CycleInput {
  bool enable = false;
  int32_t tool = 0;
  Vec3 tcp_mm = Vec3::Zero();  // workpiece frame
  // A fault of the inputs (input_not_finite, kinematics) or none.
  Fault input_fault = Fault::kNone;
  // A validated field waiting to be adopted (nullptr: none). Adopted, and
  // then owned by the state, when out.adopted is set.
  const rt::CorrectionField* candidate = nullptr;
  bool swap_inhibit = false;  // keep a candidate that would replace a field waiting
  bool reset = false;         // rising edge: clear a latched fault whose cause is gone
  // The ids of the machine, part and tool set the integrator expects a field
  // to be built for (rt::FieldIdentity); 0: not checked.
  uint32_t expect_machine = 0;
  uint32_t expect_part = 0;
  uint32_t expect_tool_set = 0;
  JointClip joint_clip;  // joint mode: the joints' limits (inactive: none)
};

struct CycleOutput {
  Vec3 correction_mm = Vec3::Zero();
  Vec3 rotation_rad = Vec3::Zero();  // the tool's rotation about the TCP
  Fault fault = Fault::kNone;
  bool limited = false;          // the magnitude clamp or the rate limit acted
  bool clamped = false;          // max-correction acted (on the target or, hard, on the output)
  bool joint_clipped = false;    // a joint's limit clipped the output this cycle
  bool active = false;           // a correction is applied or fading
  double fade = 0.0;             // gain of the current source, 0..1
  bool adopted = false;          // the candidate became the current field
  Fault latched = Fault::kNone;  // the latched fault (see latches()), until `reset`
  // A field no longer referenced by the state: retire it (free it outside
  // the servo thread). At most one per cycle.
  const rt::CorrectionField* released = nullptr;
};

// The faults that latch: the integrator's own limits were violated. The
// others describe the input or the field in this cycle and clear with their
// cause.
inline bool latches(Fault f) noexcept {
  return f == Fault::kBadParameter || f == Fault::kBoundStep;
}

namespace detail {

// Whether `field` was built for what `in` expects (every expected id that is
// not 0 equals the field's).
inline bool identity_ok(const rt::CorrectionField* field, const CycleInput& in) noexcept {
  if (field == nullptr) return true;
  const rt::FieldIdentity& id = field->identity();
  return (in.expect_machine == 0 || in.expect_machine == id.machine) &&
         (in.expect_part == 0 || in.expect_part == id.part) &&
         (in.expect_tool_set == 0 || in.expect_tool_set == id.tool_set);
}

struct Evaluated {
  Correction value;
  Fault fault = Fault::kNone;
};

inline Fault fault_of(rt::FieldStatus status) noexcept {
  switch (status) {
    case rt::FieldStatus::kOk:
      return Fault::kNone;
    case rt::FieldStatus::kOutsideGrid:
      return Fault::kOutsideGrid;
    case rt::FieldStatus::kNoLayerForTool:
      return Fault::kNoLayer;
    case rt::FieldStatus::kNonFinite:
      return Fault::kFieldNotFinite;
  }
  return Fault::kFieldNotFinite;
}

inline Evaluated evaluate(const Channel& ch, const CycleInput& in) noexcept {
  const Vec3& tcp_mm = in.tcp_mm;
  if (in.input_fault != Fault::kNone) return {ch.held, in.input_fault};
  if (ch.field == nullptr) return {ch.held, Fault::kNoField};
  if (!identity_ok(ch.field, in)) return {ch.held, Fault::kWrongField};
  const rt::FieldSample s = ch.field->evaluate(ch.tool, tcp_mm);
  const Fault f = fault_of(s.status);
  if (f != Fault::kNone) return {ch.held, f};
  return {{s.correction_mm, s.rotation_rad}, Fault::kNone};
}

// The value a channel contributes this cycle; a failure freezes it.
inline Correction channel_value(Channel& ch, const Evaluated& e) noexcept {
  if (e.fault != Fault::kNone) ch.frozen = true;
  if (ch.frozen) return ch.held;
  ch.held = e.value;
  return e.value;
}

// `c` (workpiece frame) with its joint-space components clipped to the box
// of `jc`, and no longer than `bound` (to the last ulp).
inline Limited clip_to_joint_box(const JointClip& jc, const Vec3& c, double bound) noexcept {
  const Vec3 d = jc.to_workpiece.transpose() * c;
  const Vec3 dc = d.cwiseMax(jc.lo).cwiseMin(jc.hi);
  if (dc == d) return {c, false};
  Vec3 v = limit_magnitude_hard(jc.to_workpiece * dc, bound).value;
  if (!v.allFinite()) v.setZero();  // cannot happen
  return {v, true};
}

}  // namespace detail

// The limits one shaped output obeys (unit as in Shaped).
struct ShapeLimits {
  double bound = 0.0;  // largest length
  double rate = 0.0;   // largest speed, > 0
  double accel = 0.0;  // 0: not limited
  double jerk = 0.0;   // 0: not limited
};

inline ShapeLimits translation_limits(const CompLimits& l) noexcept {
  return {l.max_correction_mm, l.max_rate_mm_per_s, l.max_accel_mm_per_s2, l.max_jerk_mm_per_s3};
}
inline ShapeLimits rotation_limits(const CompLimits& l) noexcept {
  return {l.max_tilt_rad, l.max_tilt_rate_rad_per_s, l.max_tilt_accel_rad_per_s2,
          l.max_tilt_jerk_rad_per_s3};
}

struct ShapeResult {
  Vec3 applied = Vec3::Zero();
  bool clamped = false;         // the bound acted (on the wanted value or, hard, on the output)
  bool limited = false;         // the bound, the motion limits or a joint's limit acted
  bool bound_step = false;      // the bound was lowered faster than the limits can follow
  bool clip_reported = false;   // a bound-clip this cycle or in the two before
  bool joint_clipped = false;   // a joint's limit clipped the output this cycle
  bool joint_reported = false;  // ... this cycle or, after a clip beyond the limits, shortly before
};

// One cycle of one output: clamp the wanted value `blended` to the bound
// (and to the joints' box `jc`, if any), limit its velocity, acceleration
// and jerk against the last cycle's output, then the hard bound. The
// limited output can be above the bound only when the bound was lowered
// below it; the bound wins, and a step beyond the limits is a fault.
inline ShapeResult shape(Shaped& s, const Vec3& blended, const ShapeLimits& lim,
                         const JointClip* jc, double dt_s) noexcept {
  ShapeResult res;
  Limited m = limit_magnitude(blended, lim.bound);
  // Joint mode: the wanted correction within the joints' box too, so that
  // the motion follows it within the limits; the output is clipped to the
  // box again below (as the hard bound).
  bool joint_clipped = false;
  if (jc != nullptr) {
    const Limited b = detail::clip_to_joint_box(*jc, m.value, lim.bound);
    if (b.limited) {
      m = {b.value, m.limited};
      joint_clipped = true;
    }
  }
  Limited r;
  Vec3 velocity, accel;
  if (lim.jerk > 0.0) {
    const JerkMotion mo =
        limit_motion_jerk(m.value, s.target_prev, s.target_prev2, s.output, s.velocity, s.accel,
                          lim.rate, lim.accel, lim.jerk, lim.bound, dt_s);
    r = {mo.position, mo.limited};
    velocity = mo.velocity;
    accel = mo.acceleration;
  } else {
    const Motion mo = limit_motion(m.value, s.target_prev, s.output, s.velocity, lim.rate,
                                   lim.accel, lim.bound, dt_s);
    r = {mo.position, mo.limited};
    velocity = mo.velocity;
    accel = (velocity - s.velocity) / dt_s;
  }
  s.target_prev2 = s.target_prev;
  s.target_prev = m.value;
  if (!r.value.allFinite() || !velocity.allFinite() || !accel.allFinite()) {
    // cannot happen; never pass NaN on
    r = {s.output, true};
    velocity.setZero();
    accel.setZero();
  }
  const Limited h = limit_magnitude_hard(r.value, lim.bound);
  // Whether moving the output to `p` this cycle exceeds a limit.
  constexpr double kTol = 1.0 + 1e-9;
  auto beyond_limits = [&](const Vec3& p) {
    const Vec3 v_new = (p - s.output) / dt_s;
    const Vec3 a_new = (v_new - s.velocity) / dt_s;
    return v_new.norm() > lim.rate * kTol || (lim.accel > 0.0 && a_new.norm() > lim.accel * kTol) ||
           (lim.jerk > 0.0 && (a_new - s.accel).norm() > lim.jerk * dt_s * kTol);
  };
  // (Rounding can put the output 1 ulp above the bound: the clamp removes
  // it, but that is no step.)
  if (h.limited && r.value.norm() - lim.bound > 1e-12 * (1.0 + lim.bound)) {
    const Vec3 v_new = (h.value - s.output) / dt_s;
    const Vec3 a_new = (v_new - s.velocity) / dt_s;
    const bool beyond = beyond_limits(h.value);
    // A step is a fault only in a cycle that lowered the bound; otherwise
    // the clip is the output running into the bound (or along it, faster
    // than the acceleration allows on its curvature): reported, not latched.
    res.bound_step = beyond && lim.bound < s.bound_prev;
    const bool bound_clip = beyond && !res.bound_step;
    // After a step or a clip the output starts from rest.
    velocity = beyond ? Vec3::Zero() : v_new;
    accel = beyond ? Vec3::Zero() : a_new;
    // The two cycles after a clip still show it in their differences (rest
    // after motion): reported too.
    if (bound_clip)
      s.clip_cycles = 3;
    else if (res.bound_step)
      s.clip_cycles = 0;
  }
  res.clip_reported = s.clip_cycles > 0;
  if (s.clip_cycles > 0) --s.clip_cycles;
  // Joint mode: the output within the joints' box (soft limits, per-joint
  // bounds), as the hard bound: clip, and when the clip needs more than the
  // limits allow, continue from rest. Reported in every cycle that clipped
  // the target or the output (and the two after a clip beyond the limits,
  // whose differences span it).
  Vec3 applied = h.value;
  if (jc != nullptr) {
    const Limited b = detail::clip_to_joint_box(*jc, h.value, lim.bound);
    if (b.limited) {
      applied = b.value;
      const Vec3 v_new = (applied - s.output) / dt_s;
      const Vec3 a_new = (v_new - s.velocity) / dt_s;
      const bool beyond = beyond_limits(applied);
      velocity = beyond ? Vec3::Zero() : v_new;
      accel = beyond ? Vec3::Zero() : a_new;
      s.joint_clip_cycles = std::max(s.joint_clip_cycles, beyond ? 3 : 1);
      joint_clipped = true;
    }
  }
  if (joint_clipped) s.joint_clip_cycles = std::max(s.joint_clip_cycles, 1);
  res.joint_reported = s.joint_clip_cycles > 0;
  if (s.joint_clip_cycles > 0) --s.joint_clip_cycles;
  s.output = applied;
  s.velocity = velocity;
  s.accel = accel;
  s.bound_prev = lim.bound;
  s.resting = exactly_zero(applied) && exactly_zero(velocity) && exactly_zero(accel) &&
              exactly_zero(s.target_prev) && exactly_zero(s.target_prev2);
  res.applied = applied;
  res.joint_clipped = joint_clipped;
  res.clamped = m.limited || h.limited;
  res.limited = m.limited || r.limited || h.limited || joint_clipped;
  return res;
}

inline CycleOutput step(CompState& s, const CycleInput& in, const CompLimits& raw_limits,
                        double dt_s) noexcept {
  CycleOutput out;
  // 0. A rising `reset` clears the latch; a cause still present latches
  // again at the end of this cycle.
  if (in.reset && !s.reset_prev) s.latched = Fault::kNone;
  s.reset_prev = in.reset;
  CompLimits lim;
  const bool limits_ok = adopt_limits(raw_limits, s.last_good, lim);

  // 2. A new field or tool starts a cross-fade from the current source; a
  // second change waits until the first cross-fade has finished.
  const bool outgoing_idle = s.outgoing.u <= 0.0;
  // A candidate built for another machine, part or tool set is refused
  // (it waits, reported, until a matching one replaces it).
  const bool candidate_wrong = !detail::identity_ok(in.candidate, in);
  const bool new_field = in.candidate != nullptr && !candidate_wrong &&
                         (!in.swap_inhibit || s.current.field == nullptr);
  const bool new_tool = in.tool != s.current.tool;
  if (outgoing_idle && (new_field || new_tool)) {
    if (s.current.u > 0.0)
      s.outgoing = s.current;
    else if (new_field && s.current.field != in.candidate)
      out.released = s.current.field;  // nothing to blend from
    Channel next;
    next.field = new_field ? in.candidate : s.current.field;
    next.tool = in.tool;
    s.current = next;
    out.adopted = new_field;
  }

  // 3./4. Evaluate. A current source that recovers from a failure while still
  // partly faded in cross-fades from its held value to its live value.
  const detail::Evaluated cur = detail::evaluate(s.current, in);
  if (s.current.frozen && cur.fault == Fault::kNone) {
    if (s.current.u <= 0.0) {
      s.current.frozen = false;
    } else if (s.outgoing.u <= 0.0) {
      s.outgoing = s.current;
      s.current.u = 0.0;
      s.current.frozen = false;
    }
  }
  const Correction v_cur = detail::channel_value(s.current, cur);
  Correction v_out;
  if (s.outgoing.u > 0.0)
    v_out = detail::channel_value(s.outgoing, detail::evaluate(s.outgoing, in));

  // 5. Fade and blend.
  const bool wanted = in.enable && limits_ok && s.latched == Fault::kNone && !s.current.frozen;
  s.current.u = advance_fade(s.current.u, wanted ? 1.0 : 0.0, dt_s, lim.fade_time_s);
  s.outgoing.u = advance_fade(s.outgoing.u, 0.0, dt_s, lim.fade_time_s);
  const double g_cur = fade_gain(s.current.u), g_out = fade_gain(s.outgoing.u);
  const Correction blended{g_cur * v_cur.translation_mm + g_out * v_out.translation_mm,
                           g_cur * v_cur.rotation_rad + g_out * v_out.rotation_rad};
  if (s.outgoing.u <= 0.0) {
    if (s.outgoing.field != nullptr && s.outgoing.field != s.current.field)
      out.released = s.outgoing.field;
    s.outgoing = Channel{};
  }

  // 6. Clamp, limit the motion, then the hard bound: the translation within
  // max-correction (and, in joint mode, the joints' box), the rotation
  // within max-tilt, each at its own limits.
  const ShapeResult t = shape(s.translation, blended.translation_mm, translation_limits(lim),
                              in.joint_clip.active ? &in.joint_clip : nullptr, dt_s);
  // A field without rotation leaves the rotation at rest at zero: nothing
  // to shape.
  ShapeResult r;
  if (!s.rotation.resting || !exactly_zero(blended.rotation_rad))
    r = shape(s.rotation, blended.rotation_rad, rotation_limits(lim), nullptr, dt_s);
  else
    s.rotation.bound_prev = lim.max_tilt_rad;
  if (t.joint_clipped)
    s.joint_clip_count = static_cast<int32_t>(static_cast<uint32_t>(s.joint_clip_count) + 1u);
  out.clamped = t.clamped || r.clamped;
  if (out.clamped) s.clamp_count = static_cast<int32_t>(static_cast<uint32_t>(s.clamp_count) + 1u);
  const bool bound_step = t.bound_step || r.bound_step;
  const bool clip_reported = t.clip_reported || r.clip_reported;
  const bool joint_reported = t.joint_reported;
  const Vec3 applied = t.applied;
  out.rotation_rad = r.applied;
  const bool joint_clipped = t.joint_clipped;
  out.correction_mm = applied;
  out.joint_clipped = joint_clipped;
  out.limited = t.limited || r.limited;
  out.fade = fade_gain(s.current.u);
  out.active = s.current.u > 0.0 || s.outgoing.u > 0.0 || !exactly_zero(s.translation.output) ||
               !exactly_zero(s.rotation.output);
  out.fault = in.input_fault != Fault::kNone ? in.input_fault
              : !limits_ok                   ? Fault::kBadParameter
              : bound_step                   ? Fault::kBoundStep
              : clip_reported                ? Fault::kBoundClip
              : joint_reported               ? Fault::kJointLimit
              : candidate_wrong              ? Fault::kWrongField
                                             : cur.fault;
  // Latch even when an input fault hides the latching one on `fault`.
  if (s.latched == Fault::kNone)
    s.latched = !limits_ok ? Fault::kBadParameter : bound_step ? Fault::kBoundStep : Fault::kNone;
  out.latched = s.latched;
  return out;
}

}  // namespace truecut::rt::comp
