// Probing G38.2-G38.5 and spindle-synchronised motion G33/G33.1 beyond what
// rs274 alone can show (the oracle corpus compares the calls): the probe
// result from the canon layer sets #5061-#5070 and the position, a probe
// toward the work that does not trip is an error, and the planner runs the
// probe, the rigid tap and the synchronised feed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "interp_test_util.hpp"
#include "planner_test_util.hpp"

namespace truecut::interp::testing {
namespace {

// A probe that trips `depth_mm` along the move (machine mm) and stops
// 0.1 mm further on.
ProbeFunction trips_after(double depth_mm, int* calls = nullptr) {
  return [depth_mm, calls](const ProbeRequest& r) {
    if (calls) ++*calls;
    double len = 0;
    for (int i = 0; i < 3; ++i)
      len += (r.target_mm[i] - r.start_mm[i]) * (r.target_mm[i] - r.start_mm[i]);
    len = std::sqrt(len);
    ProbeResult out;
    out.tripped = depth_mm < len;
    const double t = std::min(1.0, depth_mm / len), s = std::min(1.0, (depth_mm + 0.1) / len);
    for (int i = 0; i < 6; ++i) {
      out.trip_mm[i] = r.start_mm[i] + t * (r.target_mm[i] - r.start_mm[i]);
      out.end_mm[i] = r.start_mm[i] + s * (r.target_mm[i] - r.start_mm[i]);
    }
    return out;
  };
}

std::string message_of(const CanonProgram& p) {
  for (const CanonCall& c : p.calls)
    if (const auto* m = std::get_if<Message>(&c.op)) return m->text;
  return {};
}

TEST(Probing, TheReportedTripSetsTheParametersAndThePosition) {
  InterpreterOptions o;
  int asked = 0;
  o.probe = trips_after(4.0, &asked);
  // G55 is X+1 Y+2 Z+3: the trip point at machine Z 4 is program Z 1.
  const CanonProgram p =
      run("G21 G10 L2 P2 X1 Y2 Z3\nG55 G0 X0 Y0 Z5\nG38.2 Z-10 F100\n"
          "(DEBUG, #5061 #5062 #5063 #5070)\nG1 X1\nM2\n",
          o);
  EXPECT_EQ(asked, 1);
  EXPECT_EQ(message_of(p), " 0.000000 0.000000 1.000000 1.000000");
  // The next move starts where the machine stopped: 0.1 mm past the trip.
  const auto feeds = calls_named(p, {"STRAIGHT_FEED"});
  ASSERT_EQ(feeds.size(), 1u);
  EXPECT_EQ(feeds[0], "STRAIGHT_FEED(1.0000, 0.0000, 0.9000, 0.0000, 0.0000, 0.0000)");
  // The call carries the programmed end (printed) and the report.
  for (const CanonCall& c : p.calls)
    if (const auto* sp = std::get_if<StraightProbe>(&c.op)) {
      EXPECT_DOUBLE_EQ(sp->end.z, -10);
      EXPECT_NEAR(sp->trip.z, 1, 1e-12);
      EXPECT_NEAR(sp->stopped.z, 0.9, 1e-12);
      EXPECT_EQ(sp->kind, 2);
    }
}

TEST(Probing, AProbeTowardTheWorkThatDoesNotTripIsAnErrorAtItsLine) {
  InterpreterOptions o;
  o.probe = trips_after(100.0);
  for (const char* code : {"G38.2", "G38.4"}) {
    const std::string text = std::string("G21 G0 X0 Y0 Z5\nF100\n") + code + " Z-10\nM2\n";
    try {
      run(text, o);
      ADD_FAILURE() << code << " ran";
    } catch (const GcodeError& e) {
      EXPECT_EQ(e.where().line, 3) << e.what();
      EXPECT_NE(e.message().find(std::string(code) + ": the probe move ended without the probe"),
                std::string::npos)
          << e.what();
    }
  }
  // G38.3 and G38.5 carry on, with #5070 = 0.
  for (const char* code : {"G38.3", "G38.5"}) {
    const CanonProgram p =
        run(std::string("G21 G0 X0 Y0 Z5\nF100\n") + code + " Z-10\n(DEBUG, #5070)\nM2\n", o);
    EXPECT_EQ(message_of(p), " 0.000000") << code;
  }
}

TEST(Probing, WithoutAProbeItRunsAsRs274Alone) {
  // Never trips, no error; the machine ends 0.254 mm short of the target.
  const CanonProgram p = run("G21 G0 X0 Y0 Z5\nG38.2 Z-10 F100\n(DEBUG, #5063 #5070 #5422)\nM2\n");
  EXPECT_EQ(message_of(p), " -10.000000 0.000000 -9.746000");
}

TEST(Probing, ThePlannerRunsTheProbeToTheTripAndStopsThere) {
  InterpreterOptions o;
  o.probe = trips_after(4.0);
  const Plan plan =
      plan_program(run("G21 G0 X0 Y0 Z5\nG38.2 Z-10 F100\nG0 Z5\nM2\n", o), PlannerOptions{});
  const auto cycles = sample_plan(plan, 0.001);
  double lowest = 1e9;
  for (const CycleOutput& c : cycles)
    if (c.line >= 2) lowest = std::min(lowest, c.joints[2]);  // from the probe on
  // Down to the stop 0.1 mm past the trip at Z 1, never to the target.
  EXPECT_NEAR(lowest, 0.9, 1e-6);
}

TEST(SpindleSync, ThePlannerFeedsTheRigidTapAtKTimesSAndComesBack) {
  // K 1 mm at 600 rpm: 10 mm/s; the tap goes to Z -5 and back to Z 5.
  const Plan plan =
      plan_text("G21 G0 X0 Y0 Z5 S600 M3\nG33.1 Z-5 K1\nG0 X10\nM2\n", PlannerOptions{});
  const auto cycles = sample_plan(plan, 0.001);
  double lowest = 1e9, fastest_z = 0, z_at_x10 = 0;
  for (size_t i = 1; i < cycles.size(); ++i) {
    if (cycles[i].joints[0] > 9.999) z_at_x10 = cycles[i].joints[2];
    if (cycles[i].line != 2) continue;  // the tap's line only
    lowest = std::min(lowest, cycles[i].joints[2]);
    fastest_z =
        std::max(fastest_z, std::abs(cycles[i].joints[2] - cycles[i - 1].joints[2]) / 0.001);
  }
  EXPECT_NEAR(lowest, -5, 1e-6);
  EXPECT_NEAR(z_at_x10, 5, 1e-6);  // back where the tap started
  EXPECT_LE(fastest_z, 10.0 * (1 + 1e-6));
  EXPECT_GE(fastest_z, 9.9);
}

}  // namespace
}  // namespace truecut::interp::testing
