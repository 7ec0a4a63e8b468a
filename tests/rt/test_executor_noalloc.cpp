// The servo cycle allocates nothing: operator new and malloc are replaced in
// this test binary and counted on the servo thread while a cycle runs.
#include <gtest/gtest.h>

#include <cstdlib>

#include "alloc_counter.hpp"
#include "test_paths.hpp"
#include "truecut/rt/executor.hpp"
#include "truecut/rt/hal_file.hpp"

using namespace truecut::rt::hal;
using namespace truecut::test;

namespace {

const char* kChain =
    "loadrt threads name1=servo-thread period1=1000000\n"
    "loadrt siggen names=path\n"
    "loadrt pos_loop names=x,y\n"
    "loadrt test_counter\n"
    "loadrt recorder file=trace.csv columns=x_cmd,x_act,y_cmd,y_act,n:s32\n"
    "net xc path.cosine => x.pos-cmd recorder.0.x_cmd\n"
    "net yc path.sine => y.pos-cmd recorder.0.y_cmd test_counter.0.in\n"
    "net xa x.pos-fb => recorder.0.x_act\n"
    "net ya y.pos-fb => recorder.0.y_act\n"
    "net n test_counter.0.count => recorder.0.n\n"
    "addf path.update servo-thread\n"
    "addf x.update servo-thread\n"
    "addf y.update servo-thread\n"
    "addf test_counter.0.update servo-thread\n"
    "addf recorder.0.sample servo-thread\n";

HalOptions opts() {
  HalOptions o;
  o.component_path = {test_component_dir(), component_dir()};
  o.output_dir = scratch_dir();
  return o;
}

void allocating(void*, long) {
  void* volatile p = std::malloc(32);
  std::free(p);
}

int allocating_init(const tc_hal_api_t* api, tc_hal_t* hal, int, const char* const*, void**) {
  int id = api->component_new(hal, "bad");
  api->funct_new(hal, id, "bad.update", allocating, nullptr, 1);
  return api->component_ready(hal, id);
}

}  // namespace

TEST(NoAlloc, CounterSeesAllocations) {
  EXPECT_EQ(2u, alloc_counter_self_test());
}

TEST(NoAlloc, SimulatedServoCyclesAllocateNothing) {
  Hal hal(opts());
  load_hal_text(hal, kChain, "chain.hal");
  Executor ex(hal);
  RunLimits lim;
  lim.max_cycles = 3000;
  lim.cycle_probe = alloc_counting_probe;
  reset_alloc_counter();
  auto r = ex.run_simulated(lim);
  EXPECT_EQ(3000u, r.threads[0].cycles);
  EXPECT_EQ(0u, armed_allocations());
}

TEST(NoAlloc, WallClockServoCyclesAllocateNothing) {
  Hal hal(opts());
  load_hal_text(hal, kChain, "chain.hal");
  Executor ex(hal);
  RunLimits lim;
  lim.max_cycles = 200;
  lim.cycle_probe = alloc_counting_probe;
  WallClockOptions w;
  w.lock_memory = false;
  reset_alloc_counter();
  auto r = ex.run_wall_clock(lim, w);
  EXPECT_EQ(200u, r.threads[0].cycles);
  EXPECT_EQ(0u, armed_allocations());
}

TEST(NoAlloc, AnAllocatingComponentIsCaught) {
  Hal hal(opts());
  hal.load("bad", allocating_init, nullptr);
  hal.new_thread("servo-thread", 1'000'000);
  hal.add_function("bad.update", "servo-thread");
  Executor ex(hal);
  RunLimits lim;
  lim.max_cycles = 10;
  lim.cycle_probe = alloc_counting_probe;
  reset_alloc_counter();
  ex.run_simulated(lim);
  EXPECT_EQ(10u, armed_allocations());
}
