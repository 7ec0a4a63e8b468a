// The servo-thread executor: order, periods, limits, overruns, determinism.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>

#include "test_paths.hpp"
#include "truecut/rt/executor.hpp"
#include "truecut/rt/hal_file.hpp"

using namespace truecut::rt::hal;

namespace {

HalOptions opts(const std::filesystem::path& out = ".") {
  HalOptions o;
  o.component_path = {truecut::test::test_component_dir(), truecut::test::component_dir()};
  o.output_dir = out;
  return o;
}

// A component whose functions log (function id, period) into a fixed array.
struct CallLog {
  std::array<int, 64> id{};
  std::array<long, 64> period{};
  int n = 0;
  int stop_after = -1;  // request a stop after this many calls
};
CallLog g_log;
const tc_hal_api_t* g_api = nullptr;
tc_hal_t* g_hal = nullptr;

template <int Id>
void logged(void*, long period_ns) {
  if (g_log.n < 64) {
    g_log.id[g_log.n] = Id;
    g_log.period[g_log.n] = period_ns;
  }
  if (++g_log.n == g_log.stop_after) g_api->request_stop(g_hal);
}

int log_init(const tc_hal_api_t* api, tc_hal_t* hal, int, const char* const*, void**) {
  g_api = api;
  g_hal = hal;
  int id = api->component_new(hal, "log");
  api->funct_new(hal, id, "log.a", logged<1>, nullptr, 1);
  api->funct_new(hal, id, "log.b", logged<2>, nullptr, 1);
  api->funct_new(hal, id, "log.c", logged<3>, nullptr, 1);
  return api->component_ready(hal, id);
}

struct ExecutorTest : ::testing::Test {
  void SetUp() override { g_log = CallLog{}; }
};

}  // namespace

TEST_F(ExecutorTest, FunctionsRunInAddfOrderWithTheThreadPeriod) {
  Hal hal(opts());
  hal.load("log", log_init, nullptr);
  hal.new_thread("servo", 1'000'000);
  hal.add_function("log.b", "servo");
  hal.add_function("log.c", "servo");
  hal.add_function("log.a", "servo", 1);
  Executor ex(hal);
  RunLimits lim;
  lim.max_cycles = 2;
  ex.run_simulated(lim);
  ASSERT_EQ(6, g_log.n);
  EXPECT_EQ((std::array<int, 6>{1, 2, 3, 1, 2, 3}),
            (std::array<int, 6>{g_log.id[0], g_log.id[1], g_log.id[2], g_log.id[3], g_log.id[4],
                                g_log.id[5]}));
  for (int i = 0; i < 6; ++i)
    EXPECT_EQ(1'000'000, g_log.period[i]);
}

TEST_F(ExecutorTest, ThreadsInterleaveFastestFirstAtEqualTimes) {
  Hal hal(opts());
  hal.load("log", log_init, nullptr);
  hal.new_thread("slow", 1'000'000);  // created first, but slower
  hal.new_thread("fast", 250'000);
  hal.add_function("log.a", "slow");
  hal.add_function("log.b", "fast");
  Executor ex(hal);
  RunLimits lim;
  lim.duration_ns = 2'000'000;
  auto r = ex.run_simulated(lim);
  // t=0: fast, slow; 0.25, 0.5, 0.75: fast; t=1 ms: fast, slow; ...
  const int expected[] = {2, 1, 2, 2, 2, 2, 1, 2, 2, 2};
  ASSERT_EQ(10, g_log.n);
  for (int i = 0; i < 10; ++i) {
    EXPECT_EQ(expected[i], g_log.id[i]) << "call " << i;
    EXPECT_EQ(expected[i] == 1 ? 1'000'000 : 250'000, g_log.period[i]);
  }
  ASSERT_EQ(2u, r.threads.size());
  EXPECT_EQ("fast", r.threads[0].name);
  EXPECT_EQ(8u, r.threads[0].cycles);
  EXPECT_EQ(2u, r.threads[1].cycles);
  EXPECT_EQ(2'000'000, r.simulated_ns);
}

TEST_F(ExecutorTest, ComponentCanStopTheRunAfterTheCurrentCycle) {
  Hal hal(opts());
  hal.load("log", log_init, nullptr);
  hal.new_thread("servo", 1'000'000);
  hal.add_function("log.a", "servo");
  hal.add_function("log.b", "servo");
  g_log.stop_after = 7;  // during cycle 4
  Executor ex(hal);
  auto r = ex.run_simulated(RunLimits{});
  EXPECT_TRUE(r.stopped_by_request);
  EXPECT_EQ(4u, r.threads[0].cycles);
  EXPECT_EQ(8, g_log.n) << "the cycle in which the stop was asked completes";
}

TEST_F(ExecutorTest, TimingPinsAndCycleCounters) {
  Hal hal(opts());
  hal.load("test_busy", {});
  hal.new_thread("servo", 1'000'000);
  hal.add_function("test_busy.0.spin", "servo");
  hal.set_pin_or_param("test_busy.0.busy-ns", "20000");
  Executor ex(hal);
  RunLimits lim;
  lim.max_cycles = 3;
  ex.run_simulated(lim);
  EXPECT_GE(hal.get_pin_or_param("test_busy.0.spin.time").s, 20000);
  EXPECT_GE(hal.get_pin_or_param("test_busy.0.spin.tmax").s,
            hal.get_pin_or_param("test_busy.0.spin.time").s);
  EXPECT_GE(hal.get_pin_or_param("servo.tmax").s, 20000);
  EXPECT_EQ(3u, hal.get_pin_or_param("servo.cycles").u);
}

TEST_F(ExecutorTest, CycleLongerThanThePeriodIsCountedAsOverrunInBothModes) {
  for (bool wall : {false, true}) {
    Hal hal(opts());
    hal.load("test_busy", {});
    hal.new_thread("servo", 1'000'000);
    hal.add_function("test_busy.0.spin", "servo");
    hal.set_pin_or_param("test_busy.0.busy-ns", "3000000");  // 3x the period
    Executor ex(hal);
    RunLimits lim;
    lim.max_cycles = 5;
    WallClockOptions w;
    w.lock_memory = false;
    auto r = wall ? ex.run_wall_clock(lim, w) : ex.run_simulated(lim);
    EXPECT_EQ(5u, r.threads[0].cycles);
    EXPECT_EQ(5u, r.threads[0].overruns) << (wall ? "wall clock" : "simulated");
    EXPECT_EQ(5u, hal.get_pin_or_param("servo.overruns").u);
    EXPECT_GE(r.threads[0].compute.min_ns(), 3'000'000);
  }
}

namespace {

const char* kLoopHal =
    "loadrt threads name1=servo-thread period1=1000000\n"
    "loadrt siggen names=path\n"
    "loadrt pos_loop names=x\n"
    "loadrt recorder file=trace.csv columns=cmd,act,ferr,vel\n"
    "setp path.amplitude 50\n"
    "setp path.frequency 2\n"
    "net cmd path.sine => x.pos-cmd recorder.0.cmd\n"
    "net act x.pos-fb => recorder.0.act\n"
    "net ferr x.f-error => recorder.0.ferr\n"
    "net vel x.vel-fb => recorder.0.vel\n"
    "addf path.update servo-thread\n"
    "addf x.update servo-thread\n"
    "addf recorder.0.sample servo-thread\n";

std::string run_loop(const std::filesystem::path& dir, bool wall) {
  {
    Hal hal(opts(dir));
    load_hal_text(hal, kLoopHal, "loop.hal");
    Executor ex(hal);
    RunLimits lim;
    lim.max_cycles = 300;
    WallClockOptions w;
    w.lock_memory = false;
    auto r = wall ? ex.run_wall_clock(lim, w) : ex.run_simulated(lim);
    EXPECT_EQ(300u, r.threads[0].cycles);
  }  // the recorder finishes its file on teardown
  return truecut::test::read_file(dir / "trace.csv");
}

}  // namespace

TEST_F(ExecutorTest, SimulatedRunsAreBitForBitRepeatable) {
  auto base = truecut::test::scratch_dir();
  std::filesystem::create_directories(base / "a");
  std::filesystem::create_directories(base / "b");
  std::string a = run_loop(base / "a", false), b = run_loop(base / "b", false);
  ASSERT_EQ(301u, static_cast<size_t>(std::count(a.begin(), a.end(), '\n')));
  EXPECT_EQ(a, b);
  EXPECT_NE(std::string::npos, a.find("t,cmd,act,ferr,vel\n"));
}

TEST_F(ExecutorTest, WallClockRunComputesExactlyWhatSimulatedTimeComputes) {
  auto base = truecut::test::scratch_dir();
  std::filesystem::create_directories(base / "sim");
  std::filesystem::create_directories(base / "wall");
  std::string sim = run_loop(base / "sim", false), wall = run_loop(base / "wall", true);
  ASSERT_FALSE(sim.empty());
  EXPECT_EQ(sim, wall);
}

TEST_F(ExecutorTest, WallClockReportsWhatItObtained) {
  Hal hal(opts());
  hal.load("log", log_init, nullptr);
  hal.new_thread("servo", 1'000'000);
  hal.add_function("log.a", "servo");
  Executor ex(hal);
  RunLimits lim;
  lim.max_cycles = 3;
  WallClockOptions w;
  w.cpu = 0;
  w.fifo_priority = 10;
  w.lock_memory = false;
  auto r = ex.run_wall_clock(lim, w);
  EXPECT_EQ(3u, r.threads[0].cycles);
  EXPECT_EQ(3u, r.threads[0].latency.count());
  bool said_cpu = false, said_fifo = false;
  for (const auto& n : r.notes) {
    said_cpu |= n.find("CPU 0") != std::string::npos;
    said_fifo |= n.find("SCHED_FIFO") != std::string::npos;
  }
  EXPECT_TRUE(said_cpu);
  EXPECT_TRUE(said_fifo) << "granted or not, the report says which";
}
