// The host tells a component at exit whether any cycle ran (cycles_ran in
// hal_abi.h): 0 after a load that never ran, 1 once a thread has run one.
#include <gtest/gtest.h>

#include "truecut/rt/executor.hpp"
#include "truecut/rt/hal.hpp"

namespace rt = truecut::rt;

namespace {

int g_at_exit = -1;

int probe_init(const tc_hal_api_t* api, tc_hal_t* hal, int, const char* const*, void**) {
  const int id = api->component_new(hal, "probe");
  api->funct_new(
      hal, id, "probe.update", [](void*, long) {}, nullptr, 1);
  api->component_ready(hal, id);
  return 0;
}

void probe_exit(const tc_hal_api_t* api, tc_hal_t* hal, void*) {
  g_at_exit = api->cycles_ran(hal);
}

}  // namespace

TEST(CyclesRan, ZeroAtExitWhenNoThreadRanACycle) {
  ASSERT_TRUE(TC_HAL_API_HAS(rt::hal::Hal::api(), cycles_ran));
  g_at_exit = -1;
  {
    rt::hal::Hal h;
    h.new_thread("servo", 1'000'000);
    h.load("probe", probe_init, probe_exit);
    h.add_function("probe.update", "servo");
    EXPECT_EQ(0, h.unload());
  }
  EXPECT_EQ(0, g_at_exit);
}

TEST(CyclesRan, OneAtExitOnceACycleRanInSimulatedOrWallClockTime) {
  for (const bool wall_clock : {false, true}) {
    g_at_exit = -1;
    {
      rt::hal::Hal h;
      h.new_thread("servo", 1'000'000);
      h.load("probe", probe_init, probe_exit);
      h.add_function("probe.update", "servo");
      rt::hal::Executor ex(h);
      rt::hal::RunLimits limits;
      limits.max_cycles = 1;
      if (wall_clock) {
        rt::hal::WallClockOptions w;
        w.lock_memory = false;
        ex.run_wall_clock(limits, w);
      } else {
        ex.run_simulated(limits);
      }
      EXPECT_EQ(0, h.unload());
    }
    EXPECT_EQ(1, g_at_exit) << (wall_clock ? "wall clock" : "simulated time");
  }
}
