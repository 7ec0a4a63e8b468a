// Runs the HAL's threads: every cycle of a thread calls its functions in the
// order `addf` gave them, each with the thread's period.
//
// Two modes compute exactly the same thing:
//  - simulated time: cycles run back to back and time advances by the period
//    exactly, so a run is bit-for-bit repeatable;
//  - wall clock: a real-time thread sleeps to absolute deadlines
//    (clock_nanosleep on CLOCK_MONOTONIC), optionally under SCHED_FIFO and
//    pinned to a CPU, with memory locked, and measures wake-up latency,
//    compute time and overruns like LinuxCNC's latency test. A late cycle is
//    still computed, never skipped, so lateness changes no value.
//
// Threads with different periods are interleaved in one schedule: at equal
// times the faster thread runs first, as LinuxCNC's priorities would have it.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "truecut/rt/duration_histogram.hpp"
#include "truecut/rt/hal.hpp"

namespace truecut::rt::hal {

struct RunLimits {
  // Stop once simulated time reaches this (cycles with t < duration run);
  // <= 0 means no time limit.
  int64_t duration_ns = 0;
  // Stop after this many cycles of the fastest thread; 0 means no limit.
  uint64_t max_cycles = 0;
  // Simulated time between calls of the components' non-real-time services
  // (in wall-clock mode they run in their own thread every service_period_ns
  // of wall time).
  int64_t service_period_ns = 10'000'000;
  // Optional probe called on the servo thread right before (phase 0) and
  // right after (phase 1) each thread cycle's functions; for tracing and for
  // the tests that prove the cycle allocates nothing. Must be real-time safe.
  void (*cycle_probe)(void* user, int phase) = nullptr;
  void* cycle_probe_user = nullptr;
  // Optional progress report, called on the non-real-time side at every
  // service point with the time reached so far (simulated time, or elapsed
  // wall time in wall-clock mode).
  void (*progress)(void* user, int64_t time_ns) = nullptr;
  void* progress_user = nullptr;
};

struct WallClockOptions {
  int cpu = -1;             // pin the servo thread to this CPU; -1: no pinning
  int fifo_priority = 0;    // SCHED_FIFO priority 1..99; 0: normal scheduling
  bool lock_memory = true;  // mlockall(MCL_CURRENT | MCL_FUTURE) for the run
  // Sleep only until this long before each deadline and busy-wait the rest.
  // Trades CPU time for wake-up latency on kernels (or virtual machines)
  // whose timer wake-ups come late; 0: sleep all the way.
  int64_t spin_ns = 0;
};

struct ThreadStats {
  std::string name;
  int64_t period_ns = 0;
  uint64_t cycles = 0;
  // A cycle overran when it finished after the next release of its thread
  // (wall clock), or when its compute time exceeded the period (simulated).
  uint64_t overruns = 0;
  rt::DurationHistogram compute;  // time spent in the thread's functions
  rt::DurationHistogram latency;  // wake-up time minus deadline (wall clock)
};

struct RunReport {
  bool wall_clock = false;
  bool stopped_by_request = false;
  int64_t simulated_ns = 0;  // time of the last cycle's end
  double wall_s = 0.0;
  std::vector<ThreadStats> threads;
  // What the wall-clock setup obtained or was refused (SCHED_FIFO, affinity,
  // mlockall), in words.
  std::vector<std::string> notes;
};

class Executor {
 public:
  // Allocates all statistics up front; the HAL's threads must be final.
  explicit Executor(Hal& hal);
  ~Executor();
  Executor(const Executor&) = delete;
  Executor& operator=(const Executor&) = delete;

  RunReport run_simulated(const RunLimits& limits);
  RunReport run_wall_clock(const RunLimits& limits, const WallClockOptions& options);

  // For tests and tools: runs exactly one cycle of every thread due at the
  // next scheduled time, in simulated time, without services. Real-time safe.
  void step() noexcept;
  int64_t now_ns() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace truecut::rt::hal
