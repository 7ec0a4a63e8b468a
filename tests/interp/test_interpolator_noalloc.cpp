// The per-cycle interpolator allocates nothing (the counting allocator is
// linked into this binary) and the HAL component's servo function neither.
#include "alloc_counter.hpp"
#include "planner_test_util.hpp"
#include "truecut/rt/executor.hpp"
#include "truecut/rt/hal_file.hpp"

namespace truecut::interp::testing {
namespace {

const char* kProgram =
    "G21 G90 G64 P0.01\nG0 X0 Y0 Z5\nG1 Z0 F900\nX20 Y3\nG2 X30 Y3 R5\nG1 X40 Y10 A10\n"
    "TRAORI\nG1 X50 A20 C30\nX60 Y0 A0\nTRAFOOF\nCSPLINE\nX70 Y5\nX80 Y0\nX90 Y6\nG1\n"
    "G4 P0.1\nM2\n";

TEST(InterpolatorNoAlloc, CounterSeesAllocations) {
  EXPECT_EQ(2u, truecut::test::alloc_counter_self_test());
}

TEST(InterpolatorNoAlloc, StepAllocatesNothing) {
  const Plan plan = plan_text(kProgram);
  auto channel = std::make_unique<PlanChannel>();
  Interpolator ip;
  size_t next = 0, cycles = 0;
  truecut::test::reset_alloc_counter();
  while (!ip.output().done && cycles < 1'000'000) {
    while (next < plan.segments.size() && channel->try_push(plan.segments[next]))
      ++next;
    truecut::test::arm_alloc_counter();
    ip.step(*channel, 0.001);
    truecut::test::disarm_alloc_counter();
    ++cycles;
  }
  EXPECT_TRUE(ip.output().done);
  EXPECT_GT(cycles, 1000u);
  EXPECT_EQ(0u, truecut::test::armed_allocations());
}

TEST(InterpolatorNoAlloc, ComponentCycleAllocatesNothing) {
  const auto dir = truecut::test::scratch_dir();
  std::ofstream(dir / "p.ngc") << kProgram;
  rt::hal::HalOptions ho;
  ho.component_path = {truecut::test::component_dir()};
  ho.output_dir = dir;
  rt::hal::Hal h(ho);
  rt::hal::load_hal_text(h,
                         "loadrt threads name1=servo-thread period1=1000000\n"
                         "loadrt interp_planner program=" +
                             (dir / "p.ngc").string() +
                             "\naddf interp_planner.0.update servo-thread\n",
                         "p.hal");
  rt::hal::Executor ex(h);
  rt::hal::RunLimits lim;
  lim.max_cycles = 200'000;
  lim.cycle_probe = truecut::test::alloc_counting_probe;
  truecut::test::reset_alloc_counter();
  const auto r = ex.run_simulated(lim);
  EXPECT_TRUE(r.stopped_by_request);
  EXPECT_EQ(0u, truecut::test::armed_allocations());
}

}  // namespace
}  // namespace truecut::interp::testing
