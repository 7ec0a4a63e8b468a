// truecut_comp in a running servo loop: the cycle allocates, frees and locks
// nothing (also while fields are reloaded, swapped and retired; on each path
// of issue 19 point 7: plain, cross-fade, joint mode, fault), the same run twice is
// bit-identical, and a wall-clock run on a loaded 2-core machine (servo
// thread pinned to CPU 1 under SCHED_FIFO when permitted, a load on CPU 0) at
// 1 kHz and 8 kHz computes exactly what the simulated-time run computes.
// Nothing here asserts on time; overruns are counted and reported.
#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>

#include <atomic>
#include <cstring>
#include <mutex>
#include <thread>

#include "alloc_counter.hpp"
#include "comp_cycle_paths.hpp"
#include "test_names.hpp"
#include "test_truecut_comp_support.hpp"
#include "truecut/rt/executor.hpp"
#include "truecut/rt/hal_file.hpp"

using namespace truecut;
using namespace truecut::test;
using namespace truecut::test::comp;
using rt::hal::Hal;

namespace {

FieldSpec wide_field(double scale) {
  FieldSpec s;
  s.origin_mm = {-40.0, -40.0, -30.0};
  s.dims = {17, 17, 13};
  s.scale = scale;
  return s;
}

TEST(CompNoAlloc, CounterSeesAllocationsMadeInsideTheComponentLibrary) {
  const auto file = scratch_dir() / "f.tcf";
  write_field(file, wide_field(1.0));
  Hal h(hal_options());
  load_hal_text(h,
                "loadrt threads name1=servo-thread period1=1000000\n"
                "loadrt truecut_comp names=c field=" +
                    file.string() + "\naddf c.update servo-thread\nsetp c.reload 1\n",
                "t.hal");
  rt::hal::Executor ex(h);
  ex.step();  // the cycle sees the reload edge
  reset_alloc_counter();
  arm_alloc_counter();
  h.run_services();  // reads the file inside truecut_comp.so
  disarm_alloc_counter();
  EXPECT_GT(armed_allocations(), 0u);
}

// The counter sees what a loaded component's servo function does: a test
// component (tests/rt/plugins/test_rt_violations.c) that allocates 3 times,
// frees twice and locks 4 times per cycle, counted by the probe every other
// test here uses. Without it the zeros below could be vacuous.
TEST(CompNoAlloc, CounterSeesAllocationsFreesAndLocksOfAComponentsCycle) {
  rt::hal::HalOptions o = hal_options();
  o.component_path.insert(o.component_path.begin(), test_component_dir());
  Hal h(o);
  load_hal_text(h,
                "loadrt threads name1=servo-thread period1=1000000\n"
                "loadrt test_rt_violations\naddf test_rt_violations.0.update servo-thread\n",
                "violations.hal");
  rt::hal::Executor ex(h);
  rt::hal::RunLimits lim;
  lim.max_cycles = 10;
  lim.cycle_probe = alloc_counting_probe;
  reset_alloc_counter();
  ex.run_simulated(lim);
  EXPECT_EQ((RtViolations{30, 20, 40}), armed_violations());
}

// And what the test's own code does, armed by hand: operator new/delete,
// malloc/calloc/realloc/free, a std::mutex.
TEST(CompNoAlloc, CounterSeesAllocationsFreesAndLocksOfTheTest) {
  std::mutex m;
  reset_alloc_counter();
  arm_alloc_counter();
  auto* volatile p = new int(42);
  delete p;
  void* volatile q = std::calloc(1, 8);
  q = std::realloc(q, 32);
  std::free(q);
  { std::lock_guard lock(m); }
  disarm_alloc_counter();
  EXPECT_EQ((RtViolations{3, 2, 1}), armed_violations());
}

// Issue 19, point 7: no allocation, free or lock in a servo cycle of any
// path whose instructions rt_test_truecut_comp_callgrind counts.
class CompPathNoAlloc : public ::testing::TestWithParam<CyclePath> {};

TEST_P(CompPathNoAlloc, CyclesAllocateFreeAndLockNothing) {
  CyclePathRig rig(GetParam(), scratch_dir());
  reset_alloc_counter();
  arm_alloc_counter();
  rig.cycles(2000);
  disarm_alloc_counter();
  EXPECT_EQ(RtViolations{}, armed_violations());
  EXPECT_EQ("", rig.check());
}

INSTANTIATE_TEST_SUITE_P(Paths, CompPathNoAlloc, ::testing::ValuesIn(kAllCyclePaths),
                         [](const auto& info) { return test_name(cycle_path_name(info.param)); });

// siggen drives the TCP; `clk` toggles reload 20 times a second, so fields
// are read, published, cross-faded and retired all through the run.
TEST(CompNoAlloc, CyclesAllocateNothingWhileFieldsAreSwapped) {
  const auto file = scratch_dir() / "f.tcf";
  write_field(file, wide_field(1.0));
  Hal h(hal_options());
  load_hal_text(h,
                "loadrt threads name1=servo-thread period1=1000000\n"
                "loadrt siggen names=path,clk\n"
                "loadrt truecut_comp names=c field=" +
                    file.string() +
                    "\nloadrt pos_loop names=x,y\n"
                    "setp path.amplitude 20\nsetp clk.frequency 20\n"
                    "setp c.enable 1\nsetp c.tool 1\nsetp c.fade-time 0.02\n"
                    "net x path.cosine => c.tcp-x\nnet y path.sine => c.tcp-y\n"
                    "net reload clk.clock => c.reload\n"
                    "net xo c.tcp-x-out => x.pos-cmd\nnet yo c.tcp-y-out => y.pos-cmd\n"
                    "addf path.update servo-thread\naddf clk.update servo-thread\n"
                    "addf c.update servo-thread\naddf x.update servo-thread\n"
                    "addf y.update servo-thread\n",
                "swap.hal");
  rt::hal::Executor ex(h);
  rt::hal::RunLimits lim;
  lim.max_cycles = 1000;
  lim.service_period_ns = 1'000'000;
  lim.cycle_probe = alloc_counting_probe;
  reset_alloc_counter();
  for (int32_t tool : {1, 2, 5, 2}) {  // tool 5 has no layer: a fault path too
    h.set_pin_or_param("c.tool", std::to_string(tool));
    ex.run_simulated(lim);
  }
  EXPECT_EQ(RtViolations{}, armed_violations());
  EXPECT_GE(h.get_pin_or_param("c.field-generation").s, 60);
  EXPECT_EQ(0, h.get_pin_or_param("c.load-errors").s);
}

// The paths added for issue 19: bad parameters (NaN, negative, max-rate 0),
// bound steps under the acceleration limit, the fault latch and its reset.
TEST(CompNoAlloc, FaultLatchBoundStepsAndBadParametersAllocateNothing) {
  const auto file = scratch_dir() / "f.tcf";
  write_field(file, wide_field(20.0));
  Hal h(hal_options());
  load_hal_text(h,
                "loadrt threads name1=servo-thread period1=1000000\n"
                "loadrt siggen names=path\n"
                "loadrt truecut_comp names=c field=" +
                    file.string() +
                    "\nsetp path.amplitude 20\n"
                    "setp c.enable 1\nsetp c.tool 1\nsetp c.fade-time 0.05\n"
                    "net x path.cosine => c.tcp-x\nnet y path.sine => c.tcp-y\n"
                    "addf path.update servo-thread\naddf c.update servo-thread\n",
                "latch.hal");
  rt::hal::Executor ex(h);
  rt::hal::RunLimits lim;
  lim.max_cycles = 300;
  lim.cycle_probe = alloc_counting_probe;
  reset_alloc_counter();
  const char* steps[][2] = {{"c.max-correction", "0.5"},
                            {"c.max-correction", "0.01"},
                            {"c.reset", "1"},
                            {"c.reset", "0"},
                            {"c.max-rate", "-5"},
                            {"c.max-rate", "0"},
                            {"c.max-rate", "10"},
                            {"c.reset", "1"},
                            {"c.max-accel", "-1"},
                            {"c.max-accel", "1000"},
                            {"c.reset", "0"},
                            {"c.reset", "1"},
                            // the jerk limit: bad, then a step of the wanted
                            // correction (fade-time 0, bound raised) that it
                            // smooths, lands and clips, then off and on
                            {"c.max-jerk", "-1"},
                            {"c.max-jerk", "1e4"},
                            {"c.reset", "0"},
                            {"c.reset", "1"},
                            {"c.fade-time", "0"},
                            {"c.max-correction", "0.3"},
                            {"c.max-jerk", "0"},
                            {"c.max-jerk", "1e5"},
                            {"c.fade-time", "0.05"},
                            // a field for another machine: fades out, fault 10
                            {"c.expect-machine-id", "12345"},
                            {"c.expect-machine-id", "0"}};
  bool stepped = false, latched = false;
  for (const auto& st : steps) {
    h.set_pin_or_param(st[0], st[1]);
    ex.run_simulated(lim);
    stepped = stepped || h.get_pin_or_param("c.fault-latched").s == 8;
    latched = latched || h.get_pin_or_param("c.fault-latched").s == 6;
  }
  EXPECT_EQ(RtViolations{}, armed_violations());
  EXPECT_TRUE(stepped);
  EXPECT_TRUE(latched);
  EXPECT_EQ(0, h.get_pin_or_param("c.fault-latched").s);
  EXPECT_GT(h.get_pin_or_param("c.clamp-count").s, 0);
}

// A joint-mode truecut_comp on the wide field, X driven by siggen's cosine
// and A by its sine, with `setp` lines of the test's own.
void load_joint_mode_loop(Hal& h, const std::string& setp) {
  const auto file = scratch_dir() / "f.tcf";
  write_field(file, wide_field(1.0));
  load_hal_text(h,
                "loadrt threads name1=servo-thread period1=1000000\n"
                "loadrt siggen names=path\n"
                "loadrt truecut_comp names=c mode=joint field=" +
                    file.string() + "\nsetp path.amplitude 20\nsetp c.enable 1\nsetp c.tool 2\n" +
                    setp +
                    "net x path.cosine => c.joint-x\nnet a path.sine => c.joint-a\n"
                    "addf path.update servo-thread\naddf c.update servo-thread\n",
                "joint.hal");
}

// The allocations, frees and locks counted inside `cycles` simulated servo cycles.
RtViolations violations_in_cycles(Hal& h, std::uint64_t cycles) {
  rt::hal::Executor ex(h);
  rt::hal::RunLimits lim;
  lim.max_cycles = cycles;
  lim.cycle_probe = alloc_counting_probe;
  reset_alloc_counter();
  ex.run_simulated(lim);
  return armed_violations();
}

TEST(CompNoAlloc, JointModeCyclesAllocateNothing) {
  Hal h(hal_options());
  load_joint_mode_loop(h, "setp c.a-max 10\n");
  EXPECT_EQ(RtViolations{},
            violations_in_cycles(h, 3000));  // A leaves its travel every cycle of the sine
}

TEST(CompNoAlloc, JointLimitClipsAllocateNothing) {
  // The joints' soft limits and per-joint bounds acting (and a command
  // beyond a soft limit) every cycle of the path.
  Hal h(hal_options());
  load_joint_mode_loop(h,
                       "setp c.fade-time 0.1\nsetp c.joint-x-max-limit 5\n"
                       "setp c.joint-x-min-limit -15\nsetp c.joint-y-max-correction 0.001\n"
                       "setp c.joint-z-max-limit 0\n");
  EXPECT_EQ(RtViolations{}, violations_in_cycles(h, 3000));
  EXPECT_GT(h.get_pin_or_param("c.joint-clip-count").s, 1000);
}

// The soft-CNC loop as far as it exists today: siggen joint commands ->
// truecut_comp in joint mode (forward kinematics, correction, inverse
// kinematics) -> five pos_loop joint servos; `capture` records the correction,
// the corrected joints and the servo feedback every cycle. Field B replaces
// field A at a fixed cycle (swap-inhibit released by `gate`).
struct LoopResult {
  std::vector<double> samples;
  int32_t generation = 0;
  rt::hal::RunReport report;
  uint32_t overrun_pin = 0;
  RtViolations violations;
};

LoopResult run_loop(int64_t period_ns, uint64_t cycles, const rt::hal::WallClockOptions* wall) {
  const auto file = scratch_dir() / "loop.tcf";
  write_field(file, wide_field(1.0));
  const double span_s = double(period_ns) * 1e-9 * double(cycles);
  char setup[1024];
  std::snprintf(
      setup, sizeof setup,
      "setp path.amplitude 12\nsetp path.frequency %.17g\n"
      "setp tilt.amplitude 30\nsetp tilt.frequency %.17g\n"
      "setp gate.frequency %.17g\n"
      "setp comp.enable 1\nsetp comp.tool 1\nsetp comp.fade-time %.17g\nsetp comp.max-rate 50\n"
      "setp comp.x-rot-point 2\nsetp comp.z-rot-point 5\nsetp comp.tool-offset 10\n",
      2.0 / span_s, 1.0 / span_s, 1.0 / span_s, 0.15 * span_s);
  LoopResult r;
  Capture cap;
  {
    Hal h(hal_options());
    load_capture(h, cap, 13);
    std::string hal_text =
        "loadrt threads name1=servo-thread period1=" + std::to_string(period_ns) +
        "\nloadrt siggen names=path,tilt,gate\n"
        "loadrt truecut_comp names=comp mode=joint field=" +
        file.string() + "\nloadrt pos_loop names=x,y,z,a,c\n" + setup;
    hal_text +=
        "net jx path.cosine => comp.joint-x\nnet jy path.sine => comp.joint-y\n"
        "net jz path.triangle => comp.joint-z\nnet ja tilt.sine => comp.joint-a\n"
        "net jc tilt.sawtooth => comp.joint-c\nnet gate gate.clock => comp.swap-inhibit\n"
        "net cx comp.corr-x => capture.c0\nnet cy comp.corr-y => capture.c1\n"
        "net cz comp.corr-z => capture.c2\n";
    const char* j[] = {"x", "y", "z", "a", "c"};
    for (int i = 0; i < 5; ++i) {
      hal_text += std::string("net ") + j[i] + "-cmd comp.joint-" + j[i] + "-out => " + j[i] +
                  ".pos-cmd capture.c" + std::to_string(3 + i) + "\n";
      hal_text += std::string("net ") + j[i] + "-fb " + j[i] + ".pos-fb => capture.c" +
                  std::to_string(8 + i) + "\n";
    }
    hal_text +=
        "addf path.update servo-thread\naddf tilt.update servo-thread\n"
        "addf gate.update servo-thread\naddf comp.update servo-thread\n";
    for (int i = 0; i < 5; ++i)
      hal_text += std::string("addf ") + j[i] + ".update servo-thread\n";
    hal_text += "addf capture.sample servo-thread\n";
    load_hal_text(h, hal_text, "loop.hal");
    cap.reserve(cycles + 1);

    // Field B goes over the same file; a reload reads and publishes it
    // before the timed run, and swap-inhibit holds it until `gate` falls.
    write_field(file, wide_field(-1.5));
    h.set_pin_or_param("comp.reload", "1");
    rt::hal::Executor ex(h);
    ex.step();
    h.run_services();

    rt::hal::RunLimits lim;
    lim.max_cycles = cycles;
    lim.service_period_ns = 1'000'000;
    lim.cycle_probe = alloc_counting_probe;
    reset_alloc_counter();
    r.report = wall ? ex.run_wall_clock(lim, *wall) : ex.run_simulated(lim);
    r.violations = armed_violations();
    r.generation = h.get_pin_or_param("comp.field-generation").s;
    r.overrun_pin = h.get_pin_or_param("servo-thread.overruns").u;
  }
  r.samples = cap.samples;
  return r;
}

// Keeps CPU `cpu` busy with arithmetic and cache-missing memory traffic.
class CpuLoad {
 public:
  explicit CpuLoad(int cpu) : buffer_(4 << 20, 1.0) {
    thread_ = std::thread([this, cpu] {
      cpu_set_t set;
      CPU_ZERO(&set);
      CPU_SET(cpu, &set);
      pthread_setaffinity_np(pthread_self(), sizeof set, &set);
      double acc = 0.0;
      std::size_t i = 0;
      while (!stop_.load(std::memory_order_relaxed)) {
        for (int k = 0; k < 4096; ++k, i = (i + 4099) % buffer_.size())
          acc += buffer_[i] * 1.0000001;
        buffer_[i] = acc;
      }
    });
  }
  ~CpuLoad() {
    stop_ = true;
    thread_.join();
  }

 private:
  std::vector<double> buffer_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

void expect_identical(const std::vector<double>& a, const std::vector<double>& b) {
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(double)));
}

}  // namespace

TEST(CompDeterminism, SimulatedRunIsBitIdenticalTwiceAndSwapsAtTheGate) {
  const LoopResult a = run_loop(1'000'000, 300, nullptr);
  const LoopResult b = run_loop(1'000'000, 300, nullptr);
  EXPECT_EQ(301u * 13u, a.samples.size());
  EXPECT_EQ(2, a.generation) << "field B was adopted during the run";
  EXPECT_EQ(RtViolations{}, a.violations);
  expect_identical(a.samples, b.samples);
  // The correction is live: non-zero, and different before and after the swap.
  EXPECT_NE(0.0, a.samples[140 * 13]);
  EXPECT_NE(std::signbit(a.samples[140 * 13]), std::signbit(a.samples[300 * 13]));
}

class CompWallClock : public ::testing::TestWithParam<int64_t> {};

TEST_P(CompWallClock, LoadedTwoCoreRunComputesWhatSimulatedTimeComputes) {
  const int64_t period_ns = GetParam();
  const uint64_t cycles = period_ns == 125'000 ? 400 : 300;
  const LoopResult sim = run_loop(period_ns, cycles, nullptr);
  rt::hal::WallClockOptions w;
  w.cpu = 1;
  w.fifo_priority = 80;
  LoopResult wall;
  {
    CpuLoad load(0);
    wall = run_loop(period_ns, cycles, &w);
  }
  for (const auto& note : wall.report.notes)
    std::printf("  note: %s\n", note.c_str());
  const auto& t = wall.report.threads.at(0);
  std::printf("  %lld ns period, %llu cycles, %llu overruns, compute p99 %lld ns, max %lld ns\n",
              static_cast<long long>(period_ns), static_cast<unsigned long long>(t.cycles),
              static_cast<unsigned long long>(t.overruns),
              static_cast<long long>(t.compute.percentile_ns(0.99)),
              static_cast<long long>(t.compute.max_ns()));
  EXPECT_TRUE(wall.report.wall_clock);
  EXPECT_EQ(cycles, t.cycles);
  EXPECT_EQ(t.overruns, wall.overrun_pin) << "every overrun counted, in the report and the pin";
  EXPECT_LE(t.overruns, t.cycles);
  EXPECT_EQ(t.cycles, t.latency.count()) << "every wake-up measured";
  EXPECT_EQ(RtViolations{}, wall.violations);
  EXPECT_EQ(2, wall.generation);
  expect_identical(sim.samples, wall.samples);
}

INSTANTIATE_TEST_SUITE_P(Periods, CompWallClock, ::testing::Values(1'000'000, 125'000),
                         [](const auto& info) {
                           return info.param == 125'000 ? std::string("8kHz") : std::string("1kHz");
                         });
