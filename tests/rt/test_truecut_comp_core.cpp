// The per-cycle logic of truecut_comp without the HAL: ramp, limits, and
// rt::comp::step() on synthetic fields.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "test_truecut_comp_support.hpp"
#include "truecut/rt/comp.hpp"

using namespace truecut;
using namespace truecut::rt::comp;
using truecut::test::comp::FieldSpec;
using truecut::test::comp::make_field;

namespace {

constexpr double kDt = 0.001;  // 1 kHz
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Relative slack for comparing a step with its bound (the limit is computed
// with a division and a product).
constexpr double kSlack = 1e-12;

}  // namespace

TEST(CompMath, FadeGainIsAC2RampSymmetricAndBounded) {
  EXPECT_EQ(0.0, fade_gain(0.0));
  EXPECT_EQ(1.0, fade_gain(1.0));
  EXPECT_EQ(0.0, fade_gain(-3.0));
  EXPECT_EQ(1.0, fade_gain(7.0));
  EXPECT_EQ(0.5, fade_gain(0.5));
  const double h = 1e-4;
  double prev = 0.0;
  for (int i = 1; i <= 1000; ++i) {
    const double u = i / 1000.0;
    const double g = fade_gain(u);
    EXPECT_GE(g, prev);
    EXPECT_NEAR(1.0 - g, fade_gain(1.0 - u), 1e-14);
    const double slope = (fade_gain(u + h) - fade_gain(u - h)) / (2 * h);
    EXPECT_LE(slope, kFadeGainMaxSlope + 1e-6);
    prev = g;
  }
  // Zero velocity and acceleration at both ends.
  EXPECT_LT(fade_gain(h) / h, 1e-6);
  EXPECT_LT((1.0 - fade_gain(1.0 - h)) / h, 1e-6);
  EXPECT_LT(fade_gain(h) / (h * h), 1e-3);
}

TEST(CompMath, AdvanceFadeTakesTheFadeTimeAndNeverOvershoots) {
  double u = 0.0;
  int cycles = 0;
  while (u < 1.0 && cycles < 10000) {
    u = advance_fade(u, 1.0, kDt, 0.25);
    ++cycles;
  }
  EXPECT_EQ(1.0, u);
  EXPECT_NEAR(250, cycles, 1);
  EXPECT_EQ(0.0, advance_fade(0.0005, 0.0, kDt, 0.25) > 0.0 ? 1.0 : 0.0);
  EXPECT_EQ(1.0, advance_fade(0.0, 1.0, kDt, 0.0)) << "fade time 0 jumps";
  EXPECT_EQ(0.0, advance_fade(1.0, 0.0, kDt, kNaN)) << "a NaN fade time jumps, never NaN";
}

TEST(CompMath, MagnitudeClampKeepsDirection) {
  const Vec3 c(3.0, 4.0, 0.0);
  const Limited a = limit_magnitude(c, 10.0);
  EXPECT_FALSE(a.limited);
  EXPECT_EQ(c, a.value);
  const Limited b = limit_magnitude(c, 1.0);
  EXPECT_TRUE(b.limited);
  EXPECT_NEAR(1.0, b.value.norm(), 1e-15);
  EXPECT_NEAR(0.0, b.value.normalized().cross(c.normalized()).norm(), 1e-15);
  EXPECT_EQ(Vec3::Zero(), limit_magnitude(c, 0.0).value);
}

TEST(CompMath, RateLimitBoundsTheStepInAnyDirection) {
  std::mt19937_64 rng(6);
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> step(0.0, 0.5);
  for (int i = 0; i < 10000; ++i) {
    const Vec3 prev(n(rng), n(rng), n(rng)), target(n(rng), n(rng), n(rng));
    const double max_step = step(rng);
    const Limited r = limit_rate(target, prev, max_step);
    ASSERT_LE((r.value - prev).norm(), max_step * (1 + kSlack));
    ASSERT_EQ(r.limited, (target - prev).norm() > max_step);
    if (r.limited) {  // moved straight towards the target
      ASSERT_NEAR(0.0, (r.value - prev).cross(target - prev).norm(), 1e-12);
    } else {
      ASSERT_EQ(target, r.value);
    }
  }
}

TEST(CompMath, SanitizeReplacesInvalidTunablesBySafeValues) {
  CompLimits safe;
  EXPECT_TRUE(sanitize({0.5, 2.0, 0.3}, safe));
  EXPECT_EQ(0.5, safe.max_correction_mm);
  EXPECT_FALSE(sanitize({kNaN, 2.0, 0.3}, safe));
  EXPECT_EQ(0.0, safe.max_correction_mm);
  EXPECT_FALSE(sanitize({0.5, -1.0, 0.3}, safe));
  EXPECT_EQ(0.0, safe.max_rate_mm_per_s);
  EXPECT_FALSE(sanitize({0.5, 2.0, std::numeric_limits<double>::infinity()}, safe));
  EXPECT_EQ(0.0, safe.fade_time_s);
}

TEST(CompMath, AdoptLimitsKeepsTheLastValidValueOfEachTunable) {
  CompLimits good{0.5, 2.0, 0.3}, use;
  EXPECT_TRUE(adopt_limits({0.4, 3.0, 0.2}, good, use));
  EXPECT_EQ(0.4, use.max_correction_mm);
  EXPECT_EQ(3.0, good.max_rate_mm_per_s);
  constexpr double kInf = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(adopt_limits({kNaN, -1.0, kInf}, good, use));
  EXPECT_EQ(0.4, use.max_correction_mm);
  EXPECT_EQ(3.0, use.max_rate_mm_per_s);
  EXPECT_EQ(0.2, use.fade_time_s);
  EXPECT_FALSE(adopt_limits({0.1, 0.0, 0.0}, good, use)) << "max rate 0 could never fade out";
  EXPECT_EQ(0.1, use.max_correction_mm);
  EXPECT_EQ(3.0, use.max_rate_mm_per_s);
  EXPECT_EQ(0.0, use.fade_time_s) << "fade time 0 is valid: the rate limit does the fade";
  EXPECT_EQ(0.1, good.max_correction_mm);
}

namespace {

// Runs rt::comp::step() along a path; checks the contract every cycle.
struct Driver {
  CompState state;
  CompLimits limits{10.0, 1000.0, 0.1};
  std::vector<const rt::CorrectionField*> released;
  double max_step_mm = 0.0;
  bool ever_limited = false;

  CycleOutput cycle(const CycleInput& in) {
    const Vec3 before = state.translation.output;
    const CycleOutput o = step(state, in, limits, kDt);
    EXPECT_TRUE(o.correction_mm.allFinite());
    max_step_mm = std::max(max_step_mm, (o.correction_mm - before).norm());
    ever_limited = ever_limited || o.limited;
    if (o.released) released.push_back(o.released);
    return o;
  }
};

}  // namespace

TEST(CompCore, FadesInAndOutWithoutAJumpAndWithoutTheRateLimit) {
  const auto field = make_field({});
  const Vec3 p(1.0, 2.0, 0.5);
  const Vec3 full = field.evaluate(1, p).correction_mm;
  Driver d;
  CycleInput in;
  in.tool = 1;
  in.tcp_mm = p;
  in.candidate = &field;
  CycleOutput o = d.cycle(in);  // disabled: adopts at once, outputs nothing
  EXPECT_TRUE(o.adopted);
  EXPECT_EQ(Vec3::Zero(), o.correction_mm);
  EXPECT_FALSE(o.active);
  in.candidate = nullptr;
  in.enable = true;
  for (int i = 0; i < 100; ++i) {
    o = d.cycle(in);
    const double expect = fade_gain((i + 1) * kDt / d.limits.fade_time_s);
    ASSERT_NEAR(0.0, (o.correction_mm - expect * full).norm(), 1e-15) << i;
  }
  EXPECT_EQ(1.0, o.fade);
  EXPECT_EQ(full, o.correction_mm);
  in.enable = false;
  for (int i = 0; i < 100; ++i)
    o = d.cycle(in);
  EXPECT_EQ(Vec3::Zero(), o.correction_mm);
  EXPECT_FALSE(o.active);
  EXPECT_FALSE(d.ever_limited) << "the fade alone kept the steps small";
  EXPECT_LE(d.max_step_mm, kFadeGainMaxSlope * full.norm() * kDt / 0.1 * (1 + kSlack));
  EXPECT_TRUE(d.released.empty());
}

TEST(CompCore, ToolChangeCrossFadesFromTheOldLayerToTheNew) {
  const auto field = make_field({});
  const Vec3 p(-3.0, 4.0, 1.0);
  const Vec3 c1 = field.evaluate(1, p).correction_mm, c2 = field.evaluate(2, p).correction_mm;
  ASSERT_GT((c1 - c2).norm(), 0.02);
  Driver d;
  CycleInput in;
  in.tool = 1;
  in.tcp_mm = p;
  in.enable = true;
  in.candidate = &field;
  d.cycle(in);
  in.candidate = nullptr;
  for (int i = 0; i < 150; ++i)
    d.cycle(in);
  EXPECT_EQ(c1, d.state.translation.output);
  in.tool = 2;
  CycleOutput o;
  for (int i = 0; i < 100; ++i) {
    o = d.cycle(in);
    const double g = fade_gain((i + 1) * kDt / 0.1);
    ASSERT_NEAR(0.0, (o.correction_mm - ((1 - g) * c1 + g * c2)).norm(), 1e-14) << i;
  }
  EXPECT_EQ(c2, o.correction_mm);
  EXPECT_FALSE(d.ever_limited);
  EXPECT_LE(d.max_step_mm,
            kFadeGainMaxSlope * std::max(c1.norm(), (c1 - c2).norm()) * kDt / 0.1 * (1 + 1e-9));
}

TEST(CompCore, ASecondChangeWaitsForTheFirstCrossFade) {
  const auto field = make_field({{1, 2, 3}});
  const Vec3 p(0.0, 0.0, 0.0);
  Driver d;
  CycleInput in;
  in.tool = 1;
  in.tcp_mm = p;
  in.enable = true;
  in.candidate = &field;
  d.cycle(in);
  in.candidate = nullptr;
  for (int i = 0; i < 100; ++i)
    d.cycle(in);
  in.tool = 2;
  for (int i = 0; i < 30; ++i)
    d.cycle(in);
  in.tool = 3;
  int waited = 0;
  while (d.state.current.tool != 3 && waited < 1000) {
    const bool idle_before = d.state.outgoing.u <= 0.0;
    d.cycle(in);
    ++waited;
    ASSERT_EQ(idle_before, d.state.current.tool == 3) << "switches as soon as tool 1 is out";
  }
  EXPECT_NEAR(71, waited, 1) << "tool 1 had 70 % of its fade left";
  EXPECT_EQ(2, d.state.outgoing.tool);
  for (int i = 0; i < 100; ++i)
    d.cycle(in);
  EXPECT_EQ(field.evaluate(3, p).correction_mm, d.state.translation.output);
  EXPECT_FALSE(d.ever_limited);
}

TEST(CompCore, FieldSwapBlendsAndReleasesTheOldFieldOnceUnused) {
  FieldSpec b_spec;
  b_spec.scale = -1.5;
  const auto a = make_field({}), b = make_field(b_spec);
  const Vec3 p(5.0, -5.0, 2.0);
  Driver d;
  CycleInput in;
  in.tool = 1;
  in.tcp_mm = p;
  in.enable = true;
  in.candidate = &a;
  d.cycle(in);
  in.candidate = nullptr;
  for (int i = 0; i < 100; ++i)
    d.cycle(in);
  in.candidate = &b;
  in.swap_inhibit = true;
  for (int i = 0; i < 10; ++i)
    EXPECT_FALSE(d.cycle(in).adopted);
  in.swap_inhibit = false;
  EXPECT_TRUE(d.cycle(in).adopted);
  in.candidate = nullptr;
  for (int i = 0; i < 98; ++i)
    d.cycle(in);
  EXPECT_TRUE(d.released.empty()) << "a is still fading out";
  d.cycle(in);
  ASSERT_EQ(1u, d.released.size());
  EXPECT_EQ(&a, d.released[0]);
  EXPECT_EQ(b.evaluate(1, p).correction_mm, d.state.translation.output);
  const Vec3 ca = a.evaluate(1, p).correction_mm, cb = b.evaluate(1, p).correction_mm;
  EXPECT_LE(d.max_step_mm, kFadeGainMaxSlope * (ca - cb).norm() * kDt / 0.1 * (1 + 1e-9));
  EXPECT_FALSE(d.ever_limited);
}

TEST(CompCore, SwapWhileDisabledIsImmediate) {
  const auto a = make_field({}), b = make_field({});
  Driver d;
  CycleInput in;
  in.tool = 1;
  in.candidate = &a;
  EXPECT_TRUE(d.cycle(in).adopted);
  in.candidate = &b;
  const CycleOutput o = d.cycle(in);
  EXPECT_TRUE(o.adopted);
  ASSERT_EQ(1u, d.released.size());
  EXPECT_EQ(&a, d.released[0]);
}

TEST(CompCore, ClampAndRateLimit) {
  FieldSpec big;
  big.scale = 20.0;  // corrections of a few mm
  const auto field = make_field(big);
  const Vec3 p(2.0, 3.0, 1.0);
  const Vec3 full = field.evaluate(1, p).correction_mm;
  ASSERT_GT(full.norm(), 1.0);
  Driver d;
  d.limits = {0.5, 2.0, 0.0};  // 0.5 mm, 2 mm/s, no fade: the limits do it all
  CycleInput in;
  in.tool = 1;
  in.tcp_mm = p;
  in.enable = true;
  in.candidate = &field;
  for (int i = 1; i <= 400; ++i) {
    const CycleOutput o = d.cycle(in);
    in.candidate = nullptr;
    const double expect = std::min(0.5, i * 2.0 * kDt);
    ASSERT_NEAR(expect, o.correction_mm.norm(), 1e-12) << i;
    ASSERT_NEAR(0.0, o.correction_mm.normalized().cross(full.normalized()).norm(), 1e-12);
    ASSERT_TRUE(o.limited) << "the clamp acts even once the rate limit no longer does";
  }
  EXPECT_LE(d.max_step_mm, 2.0 * kDt * (1 + kSlack));
}

TEST(CompCore, ContinuityAlongRandomPaths) {
  // Random smooth paths that cross the grid boundary (no fading border, so
  // leaving the grid is a fault that must fade), random enable toggles, tool
  // changes to tools with and without a layer, field swaps and NaN bursts.
  FieldSpec b_spec;
  b_spec.scale = 3.0;
  const auto a = make_field({}), b = make_field(b_spec);
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    Driver d;
    d.limits = {0.4, 0.5 + 4.0 * u(rng), 0.02 + 0.3 * u(rng)};
    Vec3 amp, freq, phase;
    for (int k = 0; k < 3; ++k) {
      amp[k] = 10.0 + 20.0 * u(rng);
      freq[k] = 0.2 + 2.0 * u(rng);
      phase[k] = 6.3 * u(rng);
    }
    CycleInput in;
    in.tool = 1;
    in.candidate = &a;
    int nan_left = 0;
    for (int i = 0; i < 6000; ++i) {
      const double t = i * kDt;
      for (int k = 0; k < 3; ++k)
        in.tcp_mm[k] = amp[k] * std::sin(freq[k] * t + phase[k]);
      const double r = u(rng);
      if (r < 0.002) in.enable = !in.enable;
      if (r > 0.998) in.tool = static_cast<int32_t>(u(rng) * 4);  // 0 and 3 have no layer
      if (r > 0.4995 && r < 0.5) in.candidate = u(rng) < 0.5 ? &a : &b;
      if (r > 0.3 && r < 0.3005) nan_left = 1 + static_cast<int>(u(rng) * 20);
      in.input_fault = nan_left-- > 0 ? Fault::kInputNotFinite : Fault::kNone;
      const CycleOutput o = d.cycle(in);
      if (o.adopted) in.candidate = nullptr;
      ASSERT_LE(o.correction_mm.norm(), d.limits.max_correction_mm * (1 + kSlack));
    }
    EXPECT_LE(d.max_step_mm, d.limits.max_rate_mm_per_s * kDt * (1 + kSlack)) << seed;
  }
}

namespace {

struct PathRoughness {
  double max_step_mm = 0.0;
  double max_second_difference_mm = 0.0;
  int outside_cycles = 0;
  bool limited = false;
};

// Runs a smooth path that leaves and re-enters a field whose weight fades out
// before its boundary; measures the correction after the initial fade-in.
PathRoughness run_smooth_path(rt::FieldInterpolation interpolation) {
  FieldSpec spec;
  spec.fading_border = true;
  spec.interpolation = interpolation;
  const auto field = make_field(spec);
  Driver d;
  d.limits = {10.0, 100.0, 0.05};
  CycleInput in;
  in.tool = 2;
  in.enable = true;
  in.candidate = &field;
  PathRoughness r;
  Vec3 c_1 = Vec3::Zero(), c_2 = Vec3::Zero();
  for (int i = 0; i < 12000; ++i) {
    const double t = i * kDt;
    in.tcp_mm = Vec3(30.0 * std::sin(0.9 * t), 12.0 * std::cos(0.7 * t), 3.0 * std::sin(t));
    const CycleOutput o = d.cycle(in);
    in.candidate = nullptr;
    r.outside_cycles += o.fault == Fault::kOutsideGrid;
    if (i > 100) {
      r.max_step_mm = std::max(r.max_step_mm, (o.correction_mm - c_1).norm());
      r.max_second_difference_mm =
          std::max(r.max_second_difference_mm, (o.correction_mm - 2 * c_1 + c_2).norm());
    }
    c_2 = c_1;
    c_1 = o.correction_mm;
  }
  r.limited = d.ever_limited;
  return r;
}

}  // namespace

TEST(CompCore, SmoothPathWithFadingBorderHasNoKinkAndNeedsNoRateLimit) {
  const PathRoughness r = run_smooth_path(rt::FieldInterpolation::kTricubicBspline);
  EXPECT_GT(r.outside_cycles, 1000) << "the path leaves the grid";
  EXPECT_FALSE(r.limited);
  // Path speed <= 27 mm/s: 0.027 mm per cycle times a gradient below 0.05.
  EXPECT_LT(r.max_step_mm, 1e-3);
  // A C1 signal's second difference is O(dt^2); a kink shows a second
  // difference of the order of the step itself.
  EXPECT_LT(r.max_second_difference_mm, 0.02 * r.max_step_mm);
  // The criterion does see kinks: the C0 trilinear baseline has them at
  // every cell face.
  const PathRoughness lin = run_smooth_path(rt::FieldInterpolation::kTrilinear);
  EXPECT_GT(lin.max_second_difference_mm, 0.02 * lin.max_step_mm);
}

TEST(CompCore, FaultsFadeTheHeldCorrectionToZero) {
  const auto field = make_field({});
  const Vec3 inside(0.0, 0.0, 0.0);
  struct Case {
    const char* name;
    Fault expected;
    void (*apply)(CycleInput&, Driver&);
  };
  const Case cases[] = {
      {"no layer", Fault::kNoLayer, [](CycleInput& in, Driver&) { in.tool = 9; }},
      {"outside grid", Fault::kOutsideGrid,
       [](CycleInput& in, Driver&) { in.tcp_mm = Vec3(100.0, 0.0, 0.0); }},
      {"input not finite", Fault::kInputNotFinite,
       [](CycleInput& in, Driver&) { in.input_fault = Fault::kInputNotFinite; }},
      {"kinematics", Fault::kKinematics,
       [](CycleInput& in, Driver&) { in.input_fault = Fault::kKinematics; }},
      {"bad parameter", Fault::kBadParameter,
       [](CycleInput&, Driver& d) { d.limits.max_correction_mm = kNaN; }},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    Driver d;
    d.limits = {10.0, 50.0, 0.05};
    CycleInput in;
    in.tool = 1;
    in.enable = true;
    in.tcp_mm = inside;
    in.candidate = &field;
    d.cycle(in);
    in.candidate = nullptr;
    for (int i = 0; i < 60; ++i)
      d.cycle(in);
    const Vec3 full = d.state.translation.output;
    ASSERT_GT(full.norm(), 0.05);
    c.apply(in, d);
    CycleOutput o;
    for (int i = 0; i < 100; ++i) {
      o = d.cycle(in);
      ASSERT_EQ(c.expected, o.fault);
      ASSERT_LE(o.correction_mm.norm(), full.norm() * (1 + kSlack));
    }
    EXPECT_EQ(Vec3::Zero(), o.correction_mm);
    EXPECT_LE(d.max_step_mm, 50.0 * kDt * (1 + kSlack));
    if (c.expected != Fault::kBadParameter) {  // bad max-correction: the rate limit does it
      EXPECT_LE(d.max_step_mm, kFadeGainMaxSlope * full.norm() * kDt / 0.05 * (1 + 1e-9));
    }
  }
}

TEST(CompCore, NoFieldIsAFaultAndAFieldArrivingLaterFadesIn) {
  Driver d;
  CycleInput in;
  in.enable = true;
  in.tool = 1;
  CycleOutput o = d.cycle(in);
  EXPECT_EQ(Fault::kNoField, o.fault);
  EXPECT_EQ(Vec3::Zero(), o.correction_mm);
  const auto field = make_field({});
  in.candidate = &field;
  o = d.cycle(in);
  EXPECT_TRUE(o.adopted);
  EXPECT_EQ(Fault::kNone, o.fault);
  EXPECT_GT(o.fade, 0.0);
  EXPECT_LT(o.fade, 1e-4);
}

TEST(CompCore, OverflowingFieldIsAFieldFault) {
  // Finite node values whose B-spline prefilter overflows: the evaluation is
  // not finite.
  rt::FieldGrid g;
  rt::FieldLayer layer;
  layer.tool = 1;
  layer.nodes.assign(8, {1e308, 0.0, 0.0, 1.0});
  layer.nodes[3].dx_mm = -1e308;
  const rt::CorrectionField field(g, {layer});
  ASSERT_EQ(rt::FieldStatus::kNonFinite, field.evaluate(1, Vec3(0.5, 0.5, 0.5)).status);
  Driver d;
  CycleInput in;
  in.enable = true;
  in.tool = 1;
  in.tcp_mm = Vec3(0.5, 0.5, 0.5);
  in.candidate = &field;
  const CycleOutput o = d.cycle(in);
  EXPECT_EQ(Fault::kFieldNotFinite, o.fault);
  EXPECT_EQ(Vec3::Zero(), o.correction_mm);
}

TEST(CompCore, RecoveryFromAFaultCrossFadesFromTheHeldValue) {
  const auto field = make_field({});
  Driver d;
  d.limits = {10.0, 1000.0, 0.1};
  CycleInput in;
  in.enable = true;
  in.tool = 1;
  in.tcp_mm = Vec3(0.0, 0.0, 0.0);
  in.candidate = &field;
  d.cycle(in);
  in.candidate = nullptr;
  for (int i = 0; i < 100; ++i)
    d.cycle(in);
  in.input_fault = Fault::kInputNotFinite;
  for (int i = 0; i < 30; ++i)
    d.cycle(in);
  in.input_fault = Fault::kNone;
  in.tcp_mm = Vec3(10.0, -12.0, 4.0);  // the input comes back somewhere else
  for (int i = 0; i < 200; ++i)
    EXPECT_EQ(Fault::kNone, d.cycle(in).fault);
  EXPECT_EQ(field.evaluate(1, in.tcp_mm).correction_mm, d.state.translation.output);
  EXPECT_FALSE(d.ever_limited);
}

TEST(CompJoint, CorrectedJointsMoveTheTcpByTheCorrection) {
  rt::AcTrtParams k;
  k.x_rot_point_mm = 12.0;
  k.y_rot_point_mm = -7.0;
  k.z_rot_point_mm = 40.0;
  k.y_offset_mm = 3.0;
  k.z_offset_mm = -15.0;
  k.tool_length_mm = 80.0;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 2000; ++i) {
    const rt::AcJoints j{100 * u(rng), 100 * u(rng), 100 * u(rng), 110 * u(rng), 360 * u(rng)};
    const rt::ToolPose pose = rt::forward_ac(k, j);
    const Vec3 c(0.3 * u(rng), 0.3 * u(rng), 0.3 * u(rng));
    const rt::AcJoints out = correct_joints(k, j, pose, c);
    EXPECT_EQ(j.a_deg, out.a_deg);
    EXPECT_EQ(j.c_deg, out.c_deg);
    const rt::ToolPose moved = rt::forward_ac(k, out);
    ASSERT_NEAR(0.0, (moved.tcp_mm - (pose.tcp_mm + c)).norm(), 1e-9) << i;
    ASSERT_NEAR(0.0, (moved.axis - pose.axis).norm(), 1e-12);
    // Outside the A travel the inverse refuses; the fallback agrees.
    rt::AcTrtParams narrow = k;
    narrow.a_min_deg = narrow.a_max_deg = 1000.0;
    const rt::AcJoints fb = correct_joints(narrow, j, pose, c);
    ASSERT_NEAR(0.0, (rt::forward_ac(k, fb).tcp_mm - (pose.tcp_mm + c)).norm(), 1e-9);
  }
  const rt::AcJoints j{1, 2, 3, 4, 5};
  const rt::AcJoints same = correct_joints(k, j, rt::forward_ac(k, j), Vec3::Zero());
  EXPECT_EQ(0, std::memcmp(&j, &same, sizeof j)) << "zero correction passes joints bit for bit";
}

TEST(CompCore, InvalidParametersNeverFreezeTheOutputAndDisableAlwaysReachesZero) {
  // Each tunable NaN, infinite, negative (and max-rate 0): the fault is
  // reported, the correction fades to zero at the last valid limits, with
  // or without `enable`, and fades back in without a jump once the
  // parameter is valid again.
  const auto field = make_field({});
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const double bad[] = {kNaN, kInf, -kInf, -1.0, 0.0};
  for (int which = 0; which < 3; ++which)
    for (double b : bad) {
      if (b == 0.0 && which != 1) continue;  // 0 is a valid bound and fade time
      for (bool disable : {false, true}) {
        SCOPED_TRACE(testing::Message()
                     << "tunable " << which << " = " << b << " disable " << disable);
        Driver d;
        d.limits = {10.0, 5.0, 0.05};
        CycleInput in;
        in.tool = 1;
        in.enable = true;
        in.tcp_mm = Vec3(1.0, 1.0, 0.0);
        in.candidate = &field;
        d.cycle(in);
        in.candidate = nullptr;
        for (int i = 0; i < 100; ++i)
          d.cycle(in);
        const Vec3 full = d.state.translation.output;
        ASSERT_GT(full.norm(), 0.05);
        const CompLimits valid = d.limits;
        double* tunable[] = {&d.limits.max_correction_mm, &d.limits.max_rate_mm_per_s,
                             &d.limits.fade_time_s};
        *tunable[which] = b;
        if (disable) in.enable = false;
        CycleOutput o;
        for (int i = 0; i < 200; ++i) {
          o = d.cycle(in);
          ASSERT_EQ(Fault::kBadParameter, o.fault) << i;
        }
        EXPECT_EQ(Vec3::Zero(), o.correction_mm);
        EXPECT_FALSE(o.active);
        EXPECT_LE(d.max_step_mm, 5.0 * kDt * (1 + kSlack));
        EXPECT_EQ(Fault::kBadParameter, o.latched);
        // Recovery: latched until reset, then no jump: the correction fades
        // back in.
        d.limits = valid;
        in.enable = true;
        for (int i = 0; i < 50; ++i) {
          o = d.cycle(in);
          ASSERT_EQ(Fault::kNone, o.fault);
          ASSERT_EQ(Fault::kBadParameter, o.latched);
          ASSERT_EQ(Vec3::Zero(), o.correction_mm);
        }
        in.reset = true;
        for (int i = 0; i < 200; ++i) {
          o = d.cycle(in);
          ASSERT_EQ(Fault::kNone, o.fault);
          ASSERT_EQ(Fault::kNone, o.latched);
        }
        in.reset = false;
        EXPECT_EQ(full, d.state.translation.output);
        EXPECT_LE(d.max_step_mm, 5.0 * kDt * (1 + kSlack));
      }
    }
}

TEST(CompCore, NoJumpWhenANaNInputRecoversElsewhere) {
  // The input is NaN for a while and comes back at another place with
  // another correction: the correction cross-fades, never steps.
  FieldSpec big;
  big.scale = 20.0;
  const auto field = make_field(big);
  Driver d;
  d.limits = {5.0, 10.0, 0.1};
  CycleInput in;
  in.tool = 1;
  in.enable = true;
  in.tcp_mm = Vec3(-8.0, 6.0, 1.0);
  in.candidate = &field;
  d.cycle(in);
  in.candidate = nullptr;
  for (int i = 0; i < 200; ++i)
    d.cycle(in);
  for (int nan_cycles : {1, 5, 40, 300}) {
    in.input_fault = Fault::kInputNotFinite;
    for (int i = 0; i < nan_cycles; ++i)
      d.cycle(in);
    in.input_fault = Fault::kNone;
    in.tcp_mm = -in.tcp_mm;
    for (int i = 0; i < 300; ++i)
      d.cycle(in);
    EXPECT_EQ(field.evaluate(1, in.tcp_mm).correction_mm, d.state.translation.output) << nan_cycles;
  }
  EXPECT_LE(d.max_step_mm, 10.0 * kDt * (1 + kSlack));
}

TEST(CompCore, MaxCorrectionIsHardInEveryCycleAndAStepDownIsAFault) {
  // The probe: the bound lowered in six steps from 0.065 to 0.005 mm
  // at 1 kHz under a correction larger than all of them.
  FieldSpec big;
  big.scale = 20.0;
  const auto field = make_field(big);
  const Vec3 p(2.0, 3.0, 1.0);
  ASSERT_GT(field.evaluate(1, p).correction_mm.norm(), 0.1);
  Driver d;
  d.limits = {0.065, 10.0, 0.05};
  CycleInput in;
  in.tool = 1;
  in.tcp_mm = p;
  in.enable = true;
  in.candidate = &field;
  d.cycle(in);
  in.candidate = nullptr;
  for (int i = 0; i < 100; ++i)
    d.cycle(in);
  ASSERT_NEAR(0.065, d.state.translation.output.norm(), 1e-15);
  const int32_t clamps_before = d.state.clamp_count;
  int faults = 0;
  for (double bound : {0.05, 0.045, 0.03, 0.025, 0.01, 0.005}) {
    const double before = d.state.translation.output.norm();
    d.limits.max_correction_mm = bound;
    for (int i = 0; i < 20; ++i) {
      in.reset = i == 1;  // acknowledge a step at once (it latches)
      const CycleOutput o = d.cycle(in);
      ASSERT_LE(o.correction_mm.norm(), bound) << bound << " cycle " << i;
      ASSERT_TRUE(o.clamped);
      ASSERT_TRUE(o.limited);
      // The step is a fault exactly when it is larger than max-rate allows.
      const bool step = i == 0 && before - bound > 10.0 * kDt;
      ASSERT_EQ(step ? Fault::kBoundStep : Fault::kNone, o.fault) << bound << " cycle " << i;
      faults += o.fault == Fault::kBoundStep;
    }
  }
  EXPECT_EQ(3, faults) << "steps of 0.005 mm are within one cycle's step (0.01 mm)";
  EXPECT_EQ(clamps_before + 120, d.state.clamp_count);
  EXPECT_NEAR(0.005, d.state.translation.output.norm(), 1e-15);
  // Raising the bound again is no fault: the rate limit follows it up.
  d.limits.max_correction_mm = 0.065;
  d.max_step_mm = 0.0;
  for (int i = 0; i < 100; ++i)
    ASSERT_EQ(Fault::kNone, d.cycle(in).fault);
  EXPECT_LE(d.max_step_mm, 10.0 * kDt * (1 + kSlack));
  EXPECT_NEAR(0.065, d.state.translation.output.norm(), 1e-15);
}

TEST(CompCore, ABoundLoweredWithinTheRateIsFollowedWithoutAFault) {
  FieldSpec big;
  big.scale = 20.0;
  const auto field = make_field(big);
  Driver d;
  d.limits = {0.5, 10.0, 0.05};
  CycleInput in;
  in.tool = 1;
  in.tcp_mm = Vec3(2.0, 3.0, 1.0);
  in.enable = true;
  in.candidate = &field;
  d.cycle(in);
  in.candidate = nullptr;
  for (int i = 0; i < 100; ++i)
    d.cycle(in);
  d.max_step_mm = 0.0;
  while (d.limits.max_correction_mm > 0.01) {
    d.limits.max_correction_mm -= 0.5 * 10.0 * kDt;  // half the rate
    const CycleOutput o = d.cycle(in);
    ASSERT_EQ(Fault::kNone, o.fault);
    ASSERT_LE(o.correction_mm.norm(), d.limits.max_correction_mm);
  }
  EXPECT_LE(d.max_step_mm, 10.0 * kDt * (1 + kSlack));
}

namespace {

// Velocity and acceleration of the output, per cycle, against the limits.
struct MotionProbe {
  Vec3 c1 = Vec3::Zero(), v1 = Vec3::Zero();
  double max_v = 0.0, max_a = 0.0;
  void add(const Vec3& c) {
    const Vec3 v = (c - c1) / kDt;
    max_v = std::max(max_v, v.norm());
    max_a = std::max(max_a, (v - v1).norm() / kDt);
    c1 = c;
    v1 = v;
  }
};

}  // namespace

TEST(CompMath, LimitMotionFollowsAFeasibleTargetExactlyAndBrakesOntoAStep) {
  // A target within the limits is followed bit for bit.
  Vec3 y = Vec3::Zero(), v = Vec3::Zero(), prev = Vec3::Zero();
  for (int i = 1; i <= 1000; ++i) {
    const Vec3 t = Vec3(1.0, -0.5, 0.2) * fade_gain(i / 1000.0);
    const Motion m = limit_motion(t, prev, y, v, 10.0, 100.0, 10.0, kDt);
    ASSERT_FALSE(m.limited) << i;
    ASSERT_EQ(t, m.position);
    y = m.position;
    v = m.velocity;
    prev = t;
  }
  // Steps in random directions: velocity and acceleration stay within the
  // limits, and the output lands on the target exactly.
  std::mt19937_64 rng(19);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int k = 0; k < 50; ++k) {
    const Vec3 t(n(rng), n(rng), n(rng));
    MotionProbe probe;
    probe.c1 = y;
    probe.v1 = v;
    int cycles = 0;
    while (y != t && cycles < 20000) {
      const Motion m = limit_motion(t, t, y, v, 10.0, 100.0, 10.0, kDt);
      y = m.position;
      v = m.velocity;
      probe.add(y);
      ++cycles;
    }
    ASSERT_EQ(t, y) << k;
    EXPECT_LE(probe.max_v, 10.0 * (1 + 1e-9));
    EXPECT_LE(probe.max_a, 100.0 * (1 + 1e-6));
  }
}

namespace {

// The cases with an acceleration limit: the output's velocity and
// acceleration in every cycle.
struct AccelRig {
  FieldSpec spec;
  rt::CorrectionField field;
  Driver d;
  CycleInput in;
  MotionProbe probe;
  explicit AccelRig(double scale) : spec(with_scale(scale)), field(make_field(spec)) {
    d.limits = {1.0, 10.0, 1.0, 100.0};
    in.tool = 1;
    in.enable = true;
    in.candidate = &field;
  }
  static FieldSpec with_scale(double scale) {
    FieldSpec s;
    s.scale = scale;
    return s;
  }
  CycleOutput cycle() {
    const CycleOutput o = d.cycle(in);
    in.candidate = nullptr;
    probe.add(o.correction_mm);
    EXPECT_LE(o.correction_mm.norm(), d.limits.max_correction_mm);
    return o;
  }
};

}  // namespace

TEST(CompCore, AccelerationLimitHoldsForSwapsToolChangesFadesAndGridExit) {
  // Fade-time 0: every change of the wanted correction is a step that only
  // the limits smooth.
  AccelRig r(20.0);
  r.d.limits.max_correction_mm = 10.0;  // not clamped here (see the bound tests)
  r.d.limits.fade_time_s = 0.0;
  r.in.tcp_mm = Vec3(-3.0, 4.0, 1.0);
  for (int i = 0; i < 1000; ++i)
    r.cycle();
  EXPECT_EQ(r.field.evaluate(1, r.in.tcp_mm).correction_mm, r.d.state.translation.output);
  r.in.tool = 2;  // tool change
  for (int i = 0; i < 1000; ++i)
    r.cycle();
  r.in.tcp_mm = Vec3(100.0, 0.0, 0.0);  // leaves the grid
  for (int i = 0; i < 1000; ++i)
    EXPECT_EQ(Fault::kOutsideGrid, r.cycle().fault);
  EXPECT_EQ(Vec3::Zero(), r.d.state.translation.output);
  r.in.tcp_mm = Vec3(2.0, -2.0, 0.0);
  r.in.enable = false;
  for (int i = 0; i < 10; ++i)
    r.cycle();
  r.in.enable = true;
  for (int i = 0; i < 300; ++i)  // enable during a reversal of the disable
    r.cycle();
  r.in.enable = false;
  for (int i = 0; i < 1000; ++i)
    r.cycle();
  EXPECT_EQ(Vec3::Zero(), r.d.state.translation.output) << "disable reaches zero";
  EXPECT_LE(r.probe.max_v, 10.0 * (1 + 1e-9));
  EXPECT_LE(r.probe.max_a, 100.0 * (1 + 1e-6));
  EXPECT_TRUE(r.d.ever_limited);
}

TEST(CompCore, AccelerationLimitHoldsForAFadeReversedMidwayAndABoundRaised) {
  AccelRig r(1.0);
  r.d.limits = {1.0, 10.0, 0.02, 100.0};  // a fast fade: the limits act
  r.in.tcp_mm = Vec3(1.0, 2.0, 0.5);
  for (int i = 0; i < 10; ++i)
    r.cycle();
  r.in.enable = false;  // reversal mid-fade
  for (int i = 0; i < 8; ++i)
    r.cycle();
  r.in.enable = true;
  for (int i = 0; i < 500; ++i)
    r.cycle();
  r.d.limits.max_correction_mm = 0.5;
  for (int i = 0; i < 500; ++i)
    ASSERT_EQ(Fault::kNone, r.cycle().fault);
  EXPECT_LE(r.probe.max_v, 10.0 * (1 + 1e-9));
  EXPECT_LE(r.probe.max_a, 100.0 * (1 + 1e-6));
}

TEST(CompCore, ABoundSteppedDownStepsOnceAsAFaultThenMovesWithinTheLimits) {
  // The probe: max-correction from 0.065 to 0.005 mm in one step at
  // 1 kHz. The bound is hard: one reported step, then the output rests at
  // the bound; a bound lowered smoothly (0.5 s, C1) never steps.
  AccelRig r(20.0);
  r.d.limits = {0.065, 10.0, 1.0, 100.0};
  r.in.tcp_mm = Vec3(2.0, 3.0, 1.0);
  for (int i = 0; i < 1500; ++i)
    r.cycle();
  ASSERT_NEAR(0.065, r.d.state.translation.output.norm(), 1e-15);
  r.d.limits.max_correction_mm = 0.005;
  EXPECT_EQ(Fault::kBoundStep, r.cycle().fault);
  EXPECT_EQ(Fault::kBoundStep, r.d.state.latched);
  r.in.reset = true;  // acknowledged at once
  r.cycle();
  r.in.reset = false;
  EXPECT_EQ(Fault::kNone, r.d.state.latched);
  r.probe = MotionProbe{r.d.state.translation.output, Vec3::Zero()};
  for (int i = 0; i < 500; ++i)
    ASSERT_EQ(Fault::kNone, r.cycle().fault);
  EXPECT_LT(r.probe.max_v, 1e-9) << "at rest at the bound";
  // Up again (the limits follow), then down along a smooth ramp.
  r.d.limits.max_correction_mm = 0.065;
  for (int i = 0; i < 500; ++i)
    ASSERT_EQ(Fault::kNone, r.cycle().fault);
  ASSERT_NEAR(0.065, r.d.state.translation.output.norm(), 1e-15);
  for (int i = 1; i <= 500; ++i) {
    r.d.limits.max_correction_mm = 0.065 - 0.06 * fade_gain(i / 500.0);
    ASSERT_EQ(Fault::kNone, r.cycle().fault) << i;
  }
  EXPECT_LE(r.probe.max_v, 10.0 * (1 + 1e-9));
  EXPECT_LE(r.probe.max_a, 100.0 * (1 + 1e-6));
}

TEST(CompCore, ALatchedFaultHoldsTheCorrectionAtZeroUntilResetRises) {
  const auto field = make_field({});
  Driver d;
  d.limits = {10.0, 5.0, 0.05};
  CycleInput in;
  in.tool = 1;
  in.enable = true;
  in.candidate = &field;
  d.cycle(in);
  in.candidate = nullptr;
  for (int i = 0; i < 100; ++i)
    d.cycle(in);
  const Vec3 full = d.state.translation.output;
  ASSERT_GT(full.norm(), 0.05);
  // A reset held high does not pre-empt a fault: only its rising edge acts.
  in.reset = true;
  d.cycle(in);
  d.limits.fade_time_s = -1.0;
  CycleOutput o = d.cycle(in);
  EXPECT_EQ(Fault::kBadParameter, o.fault);
  EXPECT_EQ(Fault::kBadParameter, o.latched);
  d.limits.fade_time_s = 0.05;
  for (int i = 0; i < 300; ++i) {
    o = d.cycle(in);
    ASSERT_EQ(Fault::kBadParameter, o.latched);
  }
  EXPECT_EQ(Vec3::Zero(), o.correction_mm);
  EXPECT_FALSE(o.active);
  // A rising reset while the cause persists latches again at once.
  in.reset = false;
  d.cycle(in);
  d.limits.max_rate_mm_per_s = kNaN;
  in.reset = true;
  EXPECT_EQ(Fault::kBadParameter, d.cycle(in).latched);
  d.limits.max_rate_mm_per_s = 5.0;
  in.reset = false;
  d.cycle(in);
  EXPECT_EQ(Fault::kBadParameter, d.state.latched);
  in.reset = true;  // the cause is gone: the latch clears, the correction fades in
  for (int i = 0; i < 200; ++i)
    ASSERT_EQ(Fault::kNone, d.cycle(in).latched);
  EXPECT_EQ(full, d.state.translation.output);
  EXPECT_LE(d.max_step_mm, 5.0 * kDt * (1 + kSlack));
  // A latching fault latches even in a cycle whose `fault` shows an input
  // fault.
  in.input_fault = Fault::kInputNotFinite;
  d.limits.max_correction_mm = kNaN;
  o = d.cycle(in);
  EXPECT_EQ(Fault::kInputNotFinite, o.fault);
  EXPECT_EQ(Fault::kBadParameter, o.latched);
  in.input_fault = Fault::kNone;
  d.limits.max_correction_mm = 10.0;
  in.reset = false;
  d.cycle(in);
  in.reset = true;
  EXPECT_EQ(Fault::kNone, d.cycle(in).latched);
  // Conditions of the input or the field do not latch.
  in.tcp_mm = Vec3(100.0, 0.0, 0.0);
  EXPECT_EQ(Fault::kOutsideGrid, d.cycle(in).fault);
  EXPECT_EQ(Fault::kNone, d.state.latched);
  EXPECT_FALSE(latches(Fault::kInputNotFinite));
  EXPECT_TRUE(latches(Fault::kBoundStep));
}

TEST(CompMath, BrakingSpeedIsExactAlongABrakingRunAndNeverOvershoots) {
  // From s = braking_speed(d), one cycle at s leaves exactly s - dv_max for
  // the rest, and never more than the distance left (the smooth curve
  // through the same points let the last cycle overshoot by ~12 %).
  const double dv = 0.1, dt = kDt;
  for (int i = 1; i <= 20000; ++i) {
    const double d = i * 1e-6;
    const double s = braking_speed(d, dv, dt);
    ASSERT_LE(s * dt, d * (1 + 1e-12)) << d;
    if (s > dv) {
      ASSERT_NEAR(s - dv, braking_speed(d - s * dt, dv, dt), 1e-12 * s) << d;
    }
  }
  EXPECT_NEAR(3 * dv, braking_speed(6 * dv * dt, dv, dt), 1e-15) << "the lattice points";
  EXPECT_EQ(0.0, braking_speed(-1.0, dv, dt));
  EXPECT_EQ(0.0, braking_speed(1.0, 0.0, dt));
}

namespace {

// Velocity, acceleration and jerk of the output, per cycle (differences of
// the recorded outputs); cycles can be left out.
struct JerkProbe {
  Vec3 c1 = Vec3::Zero(), v1 = Vec3::Zero(), a1 = Vec3::Zero();
  double max_v = 0.0, max_a = 0.0, max_j = 0.0;
  Vec3 v = Vec3::Zero(), a = Vec3::Zero(), j = Vec3::Zero();  // this cycle's
  void add(const Vec3& c, bool count = true) {
    v = (c - c1) / kDt;
    a = (v - v1) / kDt;
    j = (a - a1) / kDt;
    if (count) {
      max_v = std::max(max_v, v.norm());
      max_a = std::max(max_a, a.norm());
      max_j = std::max(max_j, j.norm());
    }
    c1 = c;
    v1 = v;
    a1 = a;
  }
};

// Runs step() with the velocity, acceleration and jerk limits and checks
// every cycle: above a limit only in a cycle that reports it (bound-clip),
// or in a bound-step cycle and the two after it (which start from rest).
struct JerkRig {
  rt::CorrectionField field, other;
  Driver d;
  CycleInput in;
  JerkProbe probe;
  int excused = 0;     // cycles left that a bound step excuses
  int reported = 0;    // cycles excused by a report
  int unreported = 0;  // cycles above a limit without a report
  JerkRig(double scale, double fade_time)
      : field(make_field(with_scale(scale))), other(make_field(with_scale(-0.7 * scale))) {
    d.limits = {1.0, 10.0, fade_time, 1000.0, 1.0e5};
    in.tool = 1;
    in.enable = true;
    in.candidate = &field;
  }
  static FieldSpec with_scale(double scale) {
    FieldSpec s;
    s.scale = scale;
    return s;
  }
  CycleOutput cycle() {
    const CycleOutput o = d.cycle(in);
    if (o.adopted) in.candidate = nullptr;
    if (o.fault == Fault::kBoundStep) excused = 3;
    const bool excuse = excused > 0 || o.fault == Fault::kBoundClip;
    probe.add(o.correction_mm, !excuse);
    if (excused > 0) --excused;
    const CompLimits& l = d.limits;
    const bool above =
        probe.v.norm() > l.max_rate_mm_per_s * (1 + 1e-9) ||
        probe.a.norm() > l.max_accel_mm_per_s2 * (1 + 1e-6) ||
        (l.max_jerk_mm_per_s3 > 0.0 && probe.j.norm() > l.max_jerk_mm_per_s3 * (1 + 1e-5));
    reported += above && excuse;
    unreported += above && !excuse;
    EXPECT_LE(o.correction_mm.norm(), d.limits.max_correction_mm);
    return o;
  }
  void run(int cycles) {
    for (int i = 0; i < cycles; ++i)
      cycle();
  }
  void expect_within_limits() const {
    EXPECT_EQ(0, unreported);
    EXPECT_LE(probe.max_v, d.limits.max_rate_mm_per_s * (1 + 1e-9));
    EXPECT_LE(probe.max_a, d.limits.max_accel_mm_per_s2 * (1 + 1e-6));
    if (d.limits.max_jerk_mm_per_s3 > 0.0) {
      EXPECT_LE(probe.max_j, d.limits.max_jerk_mm_per_s3 * (1 + 1e-5));
    }
  }
};

}  // namespace

TEST(CompCore, JerkLimitHoldsInEveryTransition) {
  // Fade-time 0: every change of the wanted correction is a step that only
  // the limits smooth. Each transition of the issue in turn, on one record.
  JerkRig r(20.0, 0.0);
  r.d.limits.max_correction_mm = 10.0;  // not clamped here except where lowered
  r.in.tcp_mm = Vec3(-3.0, 4.0, 1.0);
  r.run(1000);  // enable
  EXPECT_EQ(r.field.evaluate(1, r.in.tcp_mm).correction_mm, r.d.state.translation.output)
      << "lands exactly";
  r.in.tool = 2;  // tool change
  r.run(1000);
  EXPECT_EQ(r.field.evaluate(2, r.in.tcp_mm).correction_mm, r.d.state.translation.output);
  r.in.candidate = &r.other;  // field swap
  r.run(1000);
  EXPECT_EQ(r.other.evaluate(2, r.in.tcp_mm).correction_mm, r.d.state.translation.output);
  // Grid exit while moving: 20 mm/s in x out of the grid and back.
  for (int i = 0; i < 3000; ++i) {
    r.in.tcp_mm.x() = -3.0 + 60.0 * std::sin(i * kDt / 3.0);
    r.cycle();
  }
  r.in.tcp_mm = Vec3(2.0, -2.0, 0.0);
  r.run(1000);
  // NaN input recovering elsewhere.
  r.in.input_fault = Fault::kInputNotFinite;
  r.run(7);
  r.in.input_fault = Fault::kNone;
  r.in.tcp_mm = Vec3(-12.0, 9.0, -3.0);
  r.run(1000);
  EXPECT_EQ(r.other.evaluate(2, r.in.tcp_mm).correction_mm, r.d.state.translation.output);
  // Bound lowered below the correction smoothly (within the limits), then
  // raised.
  const double full = r.d.state.translation.output.norm();
  ASSERT_GT(full, 0.5);
  for (int i = 0; i <= 1000; ++i) {
    r.d.limits.max_correction_mm = (1.0 - 0.7 * fade_gain(i / 1000.0)) * full;
    ASSERT_EQ(Fault::kNone, r.cycle().fault) << i;
  }
  r.d.limits.max_correction_mm = 10.0;
  r.run(1000);
  // Disable during an enable (a reversal), enable, disable: reaches zero.
  r.in.enable = false;
  r.run(30);
  r.in.enable = true;
  r.run(20);
  r.in.enable = false;
  r.run(1000);
  EXPECT_EQ(Vec3::Zero(), r.d.state.translation.output) << "disable reaches zero";
  r.expect_within_limits();
  EXPECT_GT(r.probe.max_j, 0.5e5) << "the jerk limit was what acted";
  EXPECT_TRUE(r.d.ever_limited);
}

TEST(CompCore, JerkLimitHoldsThroughAReportedBoundStep) {
  // The probe (0.065 -> 0.005 mm at once): one reported step, then
  // within the limits again; every other cycle within the limits.
  JerkRig r(20.0, 1.0);
  r.d.limits.max_correction_mm = 0.065;
  r.in.tcp_mm = Vec3(2.0, 3.0, 1.0);
  r.run(1500);
  ASSERT_NEAR(0.065, r.d.state.translation.output.norm(), 1e-15);
  r.d.limits.max_correction_mm = 0.005;
  EXPECT_EQ(Fault::kBoundStep, r.cycle().fault);
  r.in.reset = true;
  r.run(2000);
  r.d.limits.max_correction_mm = 0.065;
  r.run(1000);
  EXPECT_NEAR(0.065, r.d.state.translation.output.norm(), 1e-15);
  r.expect_within_limits();
}

TEST(CompCore, DefaultLimitsLeaveADefaultFadeUntouched) {
  // The HAL pins' defaults: a default fade of the largest correction the
  // default bound lets through is followed exactly.
  FieldSpec spec;
  spec.scale = 8.0;  // about 1 mm
  const auto field = make_field(spec);
  Driver d;
  d.limits = {kDefaultMaxCorrectionMm, 10.0, 1.0, kDefaultMaxAccelMmPerS2, kDefaultMaxJerkMmPerS3};
  CycleInput in;
  in.tool = 1;
  in.enable = true;
  in.tcp_mm = Vec3(0.0, 0.0, 0.0);
  in.candidate = &field;
  const Vec3 full = field.evaluate(1, in.tcp_mm).correction_mm;
  ASSERT_GT(full.norm(), 0.5);
  ASSERT_LE(full.norm(), kDefaultMaxCorrectionMm);
  for (int i = 0; i < 1500; ++i) {
    const CycleOutput o = d.cycle(in);
    in.candidate = nullptr;
    ASSERT_FALSE(o.limited) << i;
  }
  EXPECT_EQ(full, d.state.translation.output);
  in.enable = false;
  for (int i = 0; i < 1500; ++i)
    ASSERT_FALSE(d.cycle(in).limited) << i;
  EXPECT_EQ(Vec3::Zero(), d.state.translation.output);
}

TEST(CompCore, AnInvalidJerkIsABadParameter) {
  JerkRig r(1.0, 0.05);
  r.in.tcp_mm = Vec3(1.0, 1.0, 0.0);
  r.run(200);
  ASSERT_GT(r.d.state.translation.output.norm(), 0.05);
  r.d.limits.max_jerk_mm_per_s3 = -1.0;
  CycleOutput o;
  for (int i = 0; i < 500; ++i) {
    o = r.cycle();
    ASSERT_EQ(Fault::kBadParameter, o.fault);
  }
  EXPECT_EQ(Vec3::Zero(), o.correction_mm);
  r.d.limits.max_jerk_mm_per_s3 = 1.0e5;  // the last valid value was used
  r.expect_within_limits();
}

TEST(CompCore, RunningAlongTheBoundIsWithinTheLimitsOrReported) {
  // A wanted correction far above max-correction whose direction turns as
  // the tool moves: the clamped correction runs along the sphere, faster
  // than its curvature allows at max-accel. Every cycle above a limit is
  // reported (bound-clip), the clip is counted, and the bound holds.
  for (double jerk : {0.0, 1.0e4}) {
    for (double speed : {0.5, 2.0}) {
      SCOPED_TRACE(testing::Message() << "jerk " << jerk << " speed " << speed);
      JerkRig r(20.0, 0.2);
      r.d.limits = {0.5, 10.0, 0.2, 100.0, jerk};
      for (int i = 0; i < 8000; ++i) {
        const double t = i * kDt;
        r.in.tcp_mm =
            Vec3(15.0 * std::sin(speed * t), 15.0 * std::cos(0.7 * speed * t), 2.0 * std::sin(t));
        if (i == 4000) r.in.tool = 2;
        r.in.enable = i < 6000 || i >= 6300;
        r.cycle();
      }
      EXPECT_EQ(0, r.unreported);
      if (speed > 1.0) {
        EXPECT_GT(r.reported, 0) << "the case does run along the bound too fast";
      }
    }
  }
}

TEST(CompCore, AFieldBuiltForAnotherMachinePartOrToolSetIsRefused) {
  // Issue 19, point 5: the integrator sets the ids the field must name; a
  // candidate that names others is not adopted (fault wrong-field), and a
  // current field that stops matching is faded out like any field fault.
  auto a = make_field({}), b = make_field({});
  a.set_identity({0x1111, 7, 8, 9});
  b.set_identity({0x2222, 7, 8, 10});  // another tool set
  Driver d;
  d.limits = {10.0, 1000.0, 0.05};
  CycleInput in;
  in.tool = 1;
  in.enable = true;
  in.tcp_mm = Vec3(1.0, 2.0, 0.5);
  in.expect_machine = 7;
  in.expect_tool_set = 9;  // part not checked
  in.candidate = &b;
  for (int i = 0; i < 10; ++i) {
    const CycleOutput o = d.cycle(in);
    ASSERT_FALSE(o.adopted);
    ASSERT_EQ(Fault::kWrongField, o.fault);
    ASSERT_EQ(Vec3::Zero(), o.correction_mm);
  }
  in.candidate = &a;
  EXPECT_TRUE(d.cycle(in).adopted);
  in.candidate = nullptr;
  for (int i = 0; i < 100; ++i)
    ASSERT_EQ(Fault::kNone, d.cycle(in).fault);
  EXPECT_EQ(a.evaluate(1, in.tcp_mm).correction_mm, d.state.translation.output);
  // A matching candidate is adopted; a wrong one waits and is reported
  // while the current field stays applied.
  in.candidate = &b;
  for (int i = 0; i < 10; ++i) {
    const CycleOutput o = d.cycle(in);
    ASSERT_FALSE(o.adopted);
    ASSERT_EQ(Fault::kWrongField, o.fault);
  }
  EXPECT_EQ(a.evaluate(1, in.tcp_mm).correction_mm, d.state.translation.output);
  in.candidate = nullptr;
  // The expectation changes: the current field is wrong now and fades out.
  in.expect_machine = 6;
  CycleOutput o;
  for (int i = 0; i < 100; ++i) {
    o = d.cycle(in);
    ASSERT_EQ(Fault::kWrongField, o.fault);
  }
  EXPECT_EQ(Vec3::Zero(), o.correction_mm);
  EXPECT_LE(d.max_step_mm, kFadeGainMaxSlope * a.evaluate(1, in.tcp_mm).correction_mm.norm() * kDt /
                               0.05 * (1 + 1e-9));
  in.expect_machine = 0;  // not checked: it fades back in
  for (int i = 0; i < 100; ++i)
    ASSERT_EQ(Fault::kNone, d.cycle(in).fault);
  EXPECT_EQ(a.evaluate(1, in.tcp_mm).correction_mm, d.state.translation.output);
}

namespace {

// Joint mode through the core as truecut_comp runs it: joints -> TCP ->
// step() with the joints' clip box -> corrected joints clamped to the
// limits. The commanded joints move slowly along X; every cycle's
// velocity, acceleration and jerk of the correction are checked (above a
// limit only in a cycle that reports bound-clip or joint-limit).
struct JointRig {
  rt::CorrectionField field = make_field(with_scale(4.0));
  rt::AcTrtParams k;
  JointLimits limits;
  JerkRig r{4.0, 0.05};
  rt::AcJoints joints{2.0, -3.0, 4.0, 10.0, 30.0};
  rt::AcJoints out;
  CycleOutput o;
  int unreported = 0;
  JointRig() {
    k.x_rot_point_mm = 1.0;
    k.z_rot_point_mm = 2.0;
    k.tool_length_mm = 5.0;
    r.in.candidate = &field;
  }
  static FieldSpec with_scale(double scale) {
    FieldSpec s;
    s.scale = scale;
    return s;
  }
  // The joint-space correction the field wants at the joints (unclipped).
  Vec3 wanted() const {
    const rt::ToolPose pose = rt::forward_ac(k, joints);
    const JointClip jc = joint_clip(k, joints, pose, JointLimits{.max_correction = {1, 1, 1}});
    return jc.to_workpiece.transpose() * field.evaluate(1, pose.tcp_mm).correction_mm;
  }
  void cycle() {
    const rt::ToolPose pose = rt::forward_ac(k, joints);
    r.in.tcp_mm = pose.tcp_mm;
    r.in.joint_clip = joint_clip(k, joints, pose, limits);
    o = r.d.cycle(r.in);
    if (o.adopted) r.in.candidate = nullptr;
    r.probe.add(o.correction_mm);
    const CompLimits& l = r.d.limits;
    const bool above = r.probe.v.norm() > l.max_rate_mm_per_s * (1 + 1e-9) ||
                       r.probe.a.norm() > l.max_accel_mm_per_s2 * (1 + 1e-6) ||
                       r.probe.j.norm() > l.max_jerk_mm_per_s3 * (1 + 1e-5);
    unreported += above && o.fault != Fault::kJointLimit && o.fault != Fault::kBoundClip;
    out = correct_joints(k, joints, pose, o.correction_mm);
    if (r.in.joint_clip.active) clamp_joints(limits, joints, out);
  }
};

}  // namespace

TEST(CompJoint, DefaultJointLimitsLeaveTheCorrectionUntouched) {
  JointRig a, b;
  b.limits = JointLimits{};
  for (int i = 0; i < 400; ++i) {
    a.joints.x_mm = b.joints.x_mm = 2.0 + 0.001 * i;
    a.r.in.tcp_mm = rt::forward_ac(a.k, a.joints).tcp_mm;
    a.o = a.r.d.cycle(a.r.in);
    if (a.o.adopted) a.r.in.candidate = nullptr;
    b.cycle();
    ASSERT_FALSE(b.r.in.joint_clip.active);
    ASSERT_EQ(a.o.correction_mm, b.o.correction_mm) << i;
    ASSERT_EQ(Fault::kNone, b.o.fault);
  }
  EXPECT_EQ(0, b.r.d.state.joint_clip_count);
  EXPECT_GT(b.o.correction_mm.norm(), 0.1);
}

TEST(CompJoint, ASoftLimitClipsTheJointExactlyThereAndIsReported) {
  JointRig t;
  const Vec3 w = t.wanted();
  ASSERT_GT(std::abs(w.x()), 0.05);
  // X commanded 0.2 mm inside its soft limit, moving towards it at 1 mm/s;
  // the field pushes it further: the limit wins, exactly.
  const bool up = w.x() > 0.0;
  const double limit = up ? t.joints.x_mm + 0.2 : t.joints.x_mm - 0.2;
  (up ? t.limits.max_limit : t.limits.min_limit)[0] = limit;
  int clipped = 0, reported = 0;
  for (int i = 0; i < 600; ++i) {
    if (i < 150) t.joints.x_mm += (up ? 1e-3 : -1e-3);  // ends 0.05 mm inside
    t.cycle();
    const int32_t before = clipped;
    clipped += t.o.joint_clipped;
    ASSERT_EQ(before + t.o.joint_clipped, t.r.d.state.joint_clip_count) << i;
    reported += t.o.fault == Fault::kJointLimit;
    if (t.o.joint_clipped) {
      ASSERT_EQ(Fault::kJointLimit, t.o.fault) << i;
      ASSERT_TRUE(t.o.limited);
    }
    ASSERT_TRUE(up ? t.out.x_mm <= limit : t.out.x_mm >= limit) << i;
    ASSERT_LE(t.o.correction_mm.norm(), t.r.d.limits.max_correction_mm);
  }
  EXPECT_EQ(limit, t.out.x_mm) << "held exactly at the soft limit";
  EXPECT_GT(clipped, 100);
  EXPECT_GE(reported, clipped);
  EXPECT_EQ(0, t.unreported);
  EXPECT_EQ(Fault::kJointLimit, t.o.fault);
  // Y and Z keep their full correction (the field's at the joints now).
  const Vec3 w_end = t.wanted();
  const rt::ToolPose pose = rt::forward_ac(t.k, t.joints);
  const JointClip jc = joint_clip(t.k, t.joints, pose, t.limits);
  const Vec3 d = jc.to_workpiece.transpose() * t.o.correction_mm;
  EXPECT_NEAR(w_end.y(), d.y(), 1e-9);
  EXPECT_NEAR(w_end.z(), d.z(), 1e-9);
  EXPECT_NEAR(limit - t.joints.x_mm, d.x(), 1e-9);
  // The limit raised: the correction moves on to the field's value within
  // the limits, and the report clears.
  (up ? t.limits.max_limit : t.limits.min_limit)[0] = up ? limit + 10.0 : limit - 10.0;
  for (int i = 0; i < 600; ++i)
    t.cycle();
  EXPECT_EQ(Fault::kNone, t.o.fault);
  EXPECT_NEAR(0.0, (t.wanted() - jc.to_workpiece.transpose() * t.o.correction_mm).norm(), 1e-9);
  EXPECT_EQ(0, t.unreported);
}

TEST(CompJoint, APerJointMaxCorrectionBelowTheFieldsClipsThatJointOnly) {
  JointRig t;
  const Vec3 w = t.wanted();
  ASSERT_GT(std::abs(w.y()), 0.05);
  const double m = 0.3 * std::abs(w.y());
  t.limits.max_correction[1] = m;
  for (int i = 0; i < 800; ++i) {
    t.cycle();
    ASSERT_LE(t.out.y_mm, t.joints.y_mm + m) << i;
    ASSERT_GE(t.out.y_mm, t.joints.y_mm - m) << i;
  }
  EXPECT_EQ(t.joints.y_mm + std::copysign(m, w.y()), t.out.y_mm) << "exactly at the limit";
  EXPECT_TRUE(t.o.joint_clipped);
  EXPECT_EQ(Fault::kJointLimit, t.o.fault);
  EXPECT_GT(t.r.d.state.joint_clip_count, 500);
  EXPECT_EQ(0, t.unreported);
  const JointClip jc = joint_clip(t.k, t.joints, rt::forward_ac(t.k, t.joints), t.limits);
  const Vec3 d = jc.to_workpiece.transpose() * t.o.correction_mm;
  EXPECT_NEAR(w.x(), d.x(), 1e-9);
  EXPECT_NEAR(w.z(), d.z(), 1e-9);
  // An invalid per-joint limit (NaN, negative) leaves that joint uncorrected.
  for (double bad : {kNaN, -1.0}) {
    t.limits.max_correction[1] = bad;
    for (int i = 0; i < 800; ++i)
      t.cycle();
    EXPECT_EQ(t.joints.y_mm, t.out.y_mm);
    EXPECT_EQ(Fault::kJointLimit, t.o.fault);
    EXPECT_EQ(0, t.unreported);
  }
}
