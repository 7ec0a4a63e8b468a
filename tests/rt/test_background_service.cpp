// Background services (hal_abi.h, background_service_new): work that may take
// long — truecut_comp reading and checking a new field — runs in a thread of
// its own on the wall clock, so it never holds up the other services (the
// planner's refill among them); in simulated time it runs with the others,
// in registration order, so runs stay repeatable.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <vector>

#include "test_truecut_comp_support.hpp"
#include "truecut/rt/executor.hpp"
#include "truecut/rt/hal_file.hpp"

namespace {

using namespace truecut;
using namespace truecut::test::comp;
using rt::hal::Hal;
using truecut::test::scratch_dir;

int32_t gets32(const Hal& h, const std::string& pin) {
  return h.get_pin_or_param(pin).s;
}

// A component `svc` with one ordinary and one background service and a
// servo function that stops the run once the background service is done.
struct ServiceProbe {
  std::mutex mutex;
  std::condition_variable changed;
  int foreground_calls = 0;
  int background_calls = 0;
  bool block_background = false;  // first background call waits for the foreground
  bool released_by_foreground = false;
  std::atomic<bool> background_done{false};
  std::vector<char> order;  // 'f' / 'b' in call order
  const tc_hal_api_t* api = nullptr;
  tc_hal_t* hal = nullptr;
};
ServiceProbe* g_probe = nullptr;

void foreground(void*) {
  std::lock_guard<std::mutex> lock(g_probe->mutex);
  ++g_probe->foreground_calls;
  g_probe->order.push_back('f');
  g_probe->changed.notify_all();
}

void background(void*) {
  std::unique_lock<std::mutex> lock(g_probe->mutex);
  ++g_probe->background_calls;
  g_probe->order.push_back('b');
  if (g_probe->block_background && g_probe->background_calls == 1) {
    // Stands in for a large field being parsed: it returns only once the
    // ordinary services have run three more times. Run in the same loop as
    // they are, it would wait for nothing; the bound only keeps a failing
    // test from hanging.
    const int target = g_probe->foreground_calls + 3;
    g_probe->released_by_foreground = g_probe->changed.wait_for(
        lock, std::chrono::seconds(20), [&] { return g_probe->foreground_calls >= target; });
  }
  g_probe->background_done.store(true, std::memory_order_release);
}

void stop_when_done(void*, long) {
  if (g_probe->background_done.load(std::memory_order_acquire))
    g_probe->api->request_stop(g_probe->hal);
}

int probe_init(const tc_hal_api_t* api, tc_hal_t* hal, int, const char* const*, void**) {
  g_probe->api = api;
  g_probe->hal = hal;
  const int id = api->component_new(hal, "svc");
  if (api->funct_new(hal, id, "svc.check", stop_when_done, nullptr, 1) != 0) return -1;
  if (api->service_new(hal, id, foreground, nullptr) != 0) return -1;
  if (!TC_HAL_API_HAS(api, background_service_new)) return -1;
  if (api->background_service_new(hal, id, background, nullptr) != 0) return -1;
  return api->component_ready(hal, id);
}

void load_probe(Hal& hal) {
  hal.load("svc", probe_init, nullptr);
  load_hal_text(hal,
                "loadrt threads name1=servo-thread period1=1000000\n"
                "addf svc.check servo-thread\n",
                "probe.hal");
}

// Runs on the wall clock, services every 1 ms, until a component asks to
// stop (the minute is a bound for a failing run, never reached).
void run_on_the_wall_clock_until_stopped(Hal& hal) {
  rt::hal::Executor ex(hal);
  rt::hal::RunLimits limits;
  limits.service_period_ns = 1'000'000;
  limits.duration_ns = 60'000'000'000;
  rt::hal::WallClockOptions wall;
  wall.lock_memory = false;
  ex.run_wall_clock(limits, wall);
}

TEST(BackgroundService, OnTheWallClockALongOneDoesNotHoldUpTheOthers) {
  ServiceProbe probe;
  probe.block_background = true;
  g_probe = &probe;
  Hal hal(hal_options());
  load_probe(hal);
  EXPECT_EQ(1u, hal.service_count(Hal::Services::kForeground));
  EXPECT_EQ(1u, hal.service_count(Hal::Services::kBackground));
  run_on_the_wall_clock_until_stopped(hal);
  EXPECT_TRUE(probe.released_by_foreground)
      << "the ordinary services did not run while the background one was busy";
  EXPECT_TRUE(probe.background_done.load());
  g_probe = nullptr;
}

TEST(BackgroundService, InSimulatedTimeItRunsWithTheOthersInRegistrationOrder) {
  ServiceProbe probe;
  g_probe = &probe;
  Hal hal(hal_options());
  load_probe(hal);
  rt::hal::Executor ex(hal);
  rt::hal::RunLimits limits;
  limits.service_period_ns = 10'000'000;
  limits.duration_ns = 35'000'000;
  ex.run_simulated(limits);
  // The servo function stops the run in the first cycle after the first
  // service point (10 ms); then the services run once more.
  ASSERT_EQ(2, probe.foreground_calls);
  ASSERT_EQ(2, probe.background_calls);
  EXPECT_EQ((std::vector<char>{'f', 'b', 'f', 'b'}), probe.order);
  g_probe = nullptr;
}

TEST(BackgroundService, TruecutCompReadsItsFieldInTheBackground) {
  Hal hal(hal_options());
  load_hal_text(hal, "loadrt truecut_comp names=c\n", "comp.hal");
  EXPECT_EQ(1u, hal.service_count(Hal::Services::kBackground));
  EXPECT_EQ(0u, hal.service_count(Hal::Services::kForeground));
}

// A reload requested from the servo thread on the wall clock: the field is
// read by the background thread and handed over; the run stops once the
// component reports the new generation.
struct ReloadProbe {
  int32_t* generation = nullptr;
  bool* reload = nullptr;
  int32_t start_generation = -1;
  long cycles = 0;
  const tc_hal_api_t* api = nullptr;
  tc_hal_t* hal = nullptr;
};
ReloadProbe* g_reload = nullptr;

void reload_cycle(void*, long) {
  ReloadProbe& r = *g_reload;
  // The field loaded at init is adopted in the first cycle; the reload's
  // rising edge comes in the second.
  if (++r.cycles == 2) {
    r.start_generation = *r.generation;
    *r.reload = true;
  }
  if (r.cycles > 2 && *r.generation > r.start_generation) r.api->request_stop(r.hal);
}

int reload_init(const tc_hal_api_t* api, tc_hal_t* hal, int, const char* const*, void**) {
  ReloadProbe& r = *g_reload;
  r.api = api;
  r.hal = hal;
  const int id = api->component_new(hal, "rl");
  if (api->pin_new(hal, id, "rl.generation", TC_HAL_S32, TC_HAL_IN,
                   reinterpret_cast<void**>(&r.generation)) != 0)
    return -1;
  if (api->pin_new(hal, id, "rl.reload", TC_HAL_BIT, TC_HAL_OUT,
                   reinterpret_cast<void**>(&r.reload)) != 0)
    return -1;
  if (api->funct_new(hal, id, "rl.cycle", reload_cycle, nullptr, 1) != 0) return -1;
  return api->component_ready(hal, id);
}

TEST(BackgroundService, TruecutCompReloadsOnTheWallClock) {
  const auto path = write_field(scratch_dir() / "background_reload.tcf", FieldSpec{});
  ReloadProbe probe;
  g_reload = &probe;
  Hal hal(hal_options());
  hal.load("rl", reload_init, nullptr);
  load_hal_text(hal,
                "loadrt threads name1=servo-thread period1=1000000\n"
                "loadrt truecut_comp names=c field=" +
                    path.string() +
                    "\n"
                    "net gen c.field-generation => rl.generation\n"
                    "net rel rl.reload => c.reload\n"
                    "addf rl.cycle servo-thread\n"
                    "addf c.update servo-thread\n",
                "reload.hal");
  run_on_the_wall_clock_until_stopped(hal);
  EXPECT_EQ(probe.start_generation + 1, gets32(hal, "c.field-generation"));
  EXPECT_EQ(0, gets32(hal, "c.load-errors"));
  g_reload = nullptr;
}

}  // namespace
