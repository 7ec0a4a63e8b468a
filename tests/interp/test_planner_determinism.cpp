// The plan and the cycle-by-cycle setpoints are bit-for-bit repeatable.
#include <cstring>

#include "planner_test_util.hpp"

namespace truecut::interp::testing {
namespace {

const char* kProgram =
    "G21 G90 G64 P0.01\nG0 X0 Y0 Z5\nG1 Z0 F900\nX20 Y3\nG2 X30 Y3 R5\nG1 X40 Y10 A10\n"
    "TRAORI\nG1 X50 A20 C30\nX60 Y0 A0\nTRAFOOF\nBSPLINE\nX70 Y5\nX80 Y0\nX90 Y6\nG1\n"
    "G93 X100 F30\nG94\nG4 P0.1\nM2\n";

TEST(PlannerDeterminism, SameProgramSameSetpoints) {
  PlannerOptions o;
  o.kinematics.y_rot_point_mm = 3;
  const auto a = sample_plan(plan_text(kProgram, o), 0.001);
  const auto b = sample_plan(plan_text(kProgram, o), 0.001);
  ASSERT_EQ(a.size(), b.size());
  for (size_t n = 0; n < a.size(); ++n) {
    ASSERT_EQ(0, std::memcmp(a[n].joints.data(), b[n].joints.data(), sizeof a[n].joints)) << n;
    ASSERT_EQ(0, std::memcmp(a[n].tcp_mm.data(), b[n].tcp_mm.data(), sizeof a[n].tcp_mm)) << n;
    ASSERT_EQ(a[n].line, b[n].line);
  }
}

TEST(PlannerDeterminism, ChannelCapacityDoesNotChangeTheResult) {
  // Feeding the channel a few segments at a time (as a slow non-real-time
  // side would) gives the same setpoints as filling it at once.
  const Plan plan = plan_text(kProgram);
  const auto all = sample_plan(plan, 0.001);
  auto channel = std::make_unique<PlanChannel>();
  Interpolator ip;
  size_t next = 0, n = 0;
  for (; n < all.size(); ++n) {
    for (int k = 0; k < 2 && next < plan.segments.size() && channel->size() < 2; ++k)
      if (channel->try_push(plan.segments[next])) ++next;
    const CycleOutput& o = ip.step(*channel, 0.001);
    ASSERT_FALSE(o.underrun) << n;
    ASSERT_EQ(0, std::memcmp(o.joints.data(), all[n].joints.data(), sizeof o.joints)) << n;
  }
  EXPECT_TRUE(ip.output().done);
}

}  // namespace
}  // namespace truecut::interp::testing
