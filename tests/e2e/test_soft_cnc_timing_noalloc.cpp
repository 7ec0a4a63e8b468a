// Deterministic cycle timing of the whole shipped soft-CNC loop on 2 cores
// (issue 6, point 5): the real planner, truecut_comp with a field in joint
// mode, the machine, the cutting model and the recorder, run against the
// wall clock with the servo thread pinned to CPU 1 (SCHED_FIFO when the
// system grants it) while a busy thread loads CPU 0, at 1 kHz and at 8 kHz.
// The recorded trace and the machined surface must be byte-identical to the
// simulated-time run; overruns are counted and printed, never asserted
// against a threshold; no servo cycle allocates.
#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>

#include <atomic>
#include <cstdio>
#include <fstream>
#include <thread>

#include "alloc_counter.hpp"
#include "e2e_support.hpp"

using namespace truecut;
using namespace truecut::test;
using namespace truecut::test::e2e;

namespace {

namespace fs = std::filesystem;

// One climb-milling pass around the implant's shaft at z = 12 with the D2
// end mill (0.3 mm allowance): about two seconds of cutting.
const char* kProgram =
    "%\n(truecut e2e: one peripheral pass around the implant shaft)\n"
    "G21 G17 G40 G49 G80 G90 G94\nG54\nG64 P0.005\n"
    "T1 M6\nG43 H1\nS18000 M3\n"
    "G0 X-4.1 Y1.8 Z25\nG0 Z13\nG1 Z12 F300\nF500\n"
    "G1 X0.8 Y1.8\nG2 X1.8 Y0.8 I0 J-1\n"
    "G1 X1.8 Y-0.8\nG2 X0.8 Y-1.8 I-1 J0\n"
    "G1 X-0.8 Y-1.8\nG2 X-1.8 Y-0.8 I0 J1\n"
    "G1 X-1.8 Y0.8\nG2 X-0.8 Y1.8 I1 J0\n"
    "G1 X4.1 Y1.8\nG0 Z25\nM5\nG49\nM30\n%\n";

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

struct LoopRun {
  sim::SoftCncResult result;
  std::string trace;
  std::string stl;
  uint64_t allocations = 0;
};

class SoftCncTiming : public ::testing::TestWithParam<int64_t> {
 protected:
  void SetUp() override {
    if (std::thread::hardware_concurrency() < 2)
      GTEST_SKIP() << "needs 2 CPUs (servo thread on CPU 1, load on CPU 0); this machine has "
                   << std::thread::hardware_concurrency();
    dir_ = scratch_dir();
    const auto part = sim::make_part(sim::PartId::kImplant, coarse_options());
    sim::write_part(part, dir_ / "part");
    std::ofstream(dir_ / "part" / "program.ngc") << kProgram;
    // A live correction: constant plus a gradient, so every cycle evaluates
    // a non-trivial field and the inverse kinematics moves the joints.
    write_synthetic_field(dir_ / "field.tcf", part, [](const Eigen::Vector3d& p) {
      return Eigen::Vector3d(0.02 + 0.01 * p.y(), -0.01 + 0.005 * p.x(), 0.002 * p.z());
    });
  }

  LoopRun run(const std::string& name, const rt::hal::WallClockOptions* wall) {
    sim::SoftCncJob job = ideal_job(dir_ / "part", dir_ / name);
    job.field = dir_ / "field.tcf";
    job.period_us = double(GetParam()) * 1e-3;
    job.wall_clock = wall != nullptr;
    if (wall) job.wall_clock_options = *wall;
    job.cycle_probe = alloc_counting_probe;
    LoopRun r;
    reset_alloc_counter();
    r.result = sim::run_soft_cnc(job);
    r.allocations = armed_allocations();
    r.trace = read_file(dir_ / name / "trace.csv");
    r.stl = read_file(dir_ / name / "machined.stl");
    return r;
  }

  fs::path dir_;
};

TEST_P(SoftCncTiming, LoadedTwoCoreWallClockRunMachinesWhatSimulatedTimeMachines) {
  ASSERT_GT(alloc_counter_self_test(), 0u) << "the allocation counter sees nothing";
  const LoopRun sim_run = run("simulated", nullptr);
  ASSERT_TRUE(sim_run.result.finished);
  EXPECT_FALSE(sim_run.result.limit_fault);
  EXPECT_EQ(1, sim_run.result.field_generation);
  EXPECT_EQ(0u, sim_run.allocations);

  rt::hal::WallClockOptions w;
  w.cpu = 1;
  w.fifo_priority = 80;
  LoopRun wall;
  {
    CpuLoad load(0);
    wall = run("wall", &w);
  }
  const rt::hal::RunReport& rep = wall.result.report;
  for (const auto& note : rep.notes)
    std::printf("  note: %s\n", note.c_str());
  ASSERT_EQ(1u, rep.threads.size());
  const auto& t = rep.threads[0];
  std::printf(
      "  %lld ns period, program %.3f s, %llu cycles, %llu overruns; latency median %lld ns, "
      "p99 %lld ns, max %lld ns; compute median %lld ns, p99 %lld ns, max %lld ns\n",
      static_cast<long long>(GetParam()), wall.result.program_s,
      static_cast<unsigned long long>(t.cycles), static_cast<unsigned long long>(t.overruns),
      static_cast<long long>(t.latency.percentile_ns(0.5)),
      static_cast<long long>(t.latency.percentile_ns(0.99)),
      static_cast<long long>(t.latency.max_ns()),
      static_cast<long long>(t.compute.percentile_ns(0.5)),
      static_cast<long long>(t.compute.percentile_ns(0.99)),
      static_cast<long long>(t.compute.max_ns()));

  EXPECT_TRUE(rep.wall_clock);
  EXPECT_TRUE(wall.result.finished);
  EXPECT_EQ(sim_run.result.report.threads.at(0).cycles, t.cycles);
  EXPECT_EQ(t.cycles, t.latency.count()) << "every wake-up measured";
  EXPECT_LE(t.overruns, t.cycles);
  EXPECT_EQ(0u, wall.allocations);
  EXPECT_FALSE(sim_run.trace.empty());
  EXPECT_TRUE(sim_run.trace == wall.trace) << "trace.csv differs between simulated and wall clock";
  EXPECT_TRUE(sim_run.stl == wall.stl) << "machined.stl differs between simulated and wall clock";
}

INSTANTIATE_TEST_SUITE_P(Periods, SoftCncTiming, ::testing::Values(1'000'000, 125'000),
                         [](const auto& info) {
                           return info.param == 125'000 ? std::string("8kHz") : std::string("1kHz");
                         });

}  // namespace
