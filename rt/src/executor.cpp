#include "truecut/rt/executor.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <time.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <thread>

#include "hal_state.hpp"

using namespace truecut::rt::hal::detail;

namespace truecut::rt::hal {
namespace {

int64_t mono_ns() noexcept {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return int64_t(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

int32_t clamp_s32(int64_t v) noexcept {
  return static_cast<int32_t>(std::min<int64_t>(v, INT32_MAX));
}

void sleep_until_ns(int64_t t_ns) noexcept {
  timespec ts{static_cast<time_t>(t_ns / 1'000'000'000), static_cast<long>(t_ns % 1'000'000'000)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

// Touches stack pages now so that the first deep call in a cycle does not
// page-fault.
__attribute__((noinline)) void prefault_stack() {
  volatile unsigned char buf[256 * 1024];
  for (size_t i = 0; i < sizeof buf; i += 4096)
    buf[i] = 0;
}

}  // namespace

struct Executor::Impl {
  struct Slot {
    Thread* thread;
    ThreadStats* stats;
    int64_t next_ns;
  };

  Hal& hal;
  tc_hal& st;
  std::vector<ThreadStats> stats;
  std::vector<Slot> slots;  // fastest thread first

  explicit Impl(Hal& h) : hal(h), st(*h.state()) {
    std::vector<Thread*> ths;
    for (auto& t : st.threads)
      ths.push_back(t.get());
    std::stable_sort(ths.begin(), ths.end(),
                     [](const Thread* a, const Thread* b) { return a->period_ns < b->period_ns; });
    stats.resize(ths.size());
    for (size_t i = 0; i < ths.size(); ++i) {
      stats[i].name = ths[i]->name;
      stats[i].period_ns = ths[i]->period_ns;
      slots.push_back({ths[i], &stats[i], 0});
    }
  }

  void reset() {
    for (auto& s : slots) {
      s.next_ns = 0;
      s.stats->cycles = s.stats->overruns = 0;
      s.stats->compute.clear();
      s.stats->latency.clear();
    }
    hal.clear_stop();
  }

  size_t next_slot() const noexcept {
    size_t best = 0;
    for (size_t i = 1; i < slots.size(); ++i)
      if (slots[i].next_ns < slots[best].next_ns) best = i;
    return best;
  }

  bool finished(const RunLimits& lim) const noexcept {
    if (slots.empty()) return true;
    if (lim.duration_ns > 0 && slots[next_slot()].next_ns >= lim.duration_ns) return true;
    if (lim.max_cycles > 0 && slots[0].stats->cycles >= lim.max_cycles) return true;
    return false;
  }

  // One cycle of one thread: its functions in order, with timing pins.
  int64_t run_cycle(Slot& s, const RunLimits& lim) noexcept {
    Thread& th = *s.thread;
    if (lim.cycle_probe) lim.cycle_probe(lim.cycle_probe_user, 0);
    const int64_t t0 = mono_ns();
    int64_t prev = t0;
    for (Funct* f : th.functs) {
      f->fn(f->arg, static_cast<long>(th.period_ns));
      const int64_t t = mono_ns();
      const int32_t dt = clamp_s32(t - prev);
      *static_cast<int32_t*>(f->time_pin) = dt;
      const bool increased = dt > f->tmax_ns;
      if (increased) f->tmax_ns = dt;
      f->tmax_increased = increased;
      prev = t;
    }
    if (lim.cycle_probe) lim.cycle_probe(lim.cycle_probe_user, 1);
    const int64_t compute = prev - t0;
    *static_cast<int32_t*>(th.time_pin) = clamp_s32(compute);
    th.tmax_ns = std::max(th.tmax_ns, clamp_s32(compute));
    *static_cast<uint32_t*>(th.cycles_pin) += 1;
    s.stats->compute.add(compute);
    s.stats->cycles++;
    s.next_ns += th.period_ns;
    st.cycles_ran.store(true, std::memory_order_relaxed);
    return compute;
  }

  void count_overrun(Slot& s) noexcept {
    s.stats->overruns++;
    *static_cast<uint32_t*>(s.thread->overruns_pin) += 1;
  }

  RunReport report(bool wall, double wall_s) const {
    RunReport r;
    r.wall_clock = wall;
    r.stopped_by_request = hal.stop_requested();
    r.simulated_ns = slots.empty() ? 0 : slots[0].next_ns;
    r.wall_s = wall_s;
    r.threads = stats;
    return r;
  }
};

Executor::Executor(Hal& hal) : impl_(std::make_unique<Impl>(hal)) {}
Executor::~Executor() = default;

int64_t Executor::now_ns() const noexcept {
  return impl_->slots.empty() ? 0 : impl_->slots[impl_->next_slot()].next_ns;
}

void Executor::step() noexcept {
  if (impl_->slots.empty()) return;
  Impl::Slot& s = impl_->slots[impl_->next_slot()];
  if (impl_->run_cycle(s, RunLimits{}) > s.thread->period_ns) impl_->count_overrun(s);
}

RunReport Executor::run_simulated(const RunLimits& limits) {
  Impl& im = *impl_;
  im.reset();
  const int64_t wall0 = mono_ns();
  const int64_t service_period = std::max<int64_t>(limits.service_period_ns, 1);
  int64_t next_service_ns = service_period;
  while (!im.finished(limits)) {
    Impl::Slot& s = im.slots[im.next_slot()];
    const int64_t t = s.next_ns;
    if (im.run_cycle(s, limits) > s.thread->period_ns) im.count_overrun(s);
    if (im.hal.stop_requested()) break;
    if (t + s.thread->period_ns >= next_service_ns) {
      im.hal.run_services();
      if (limits.progress) limits.progress(limits.progress_user, t + s.thread->period_ns);
      next_service_ns += service_period;
    }
  }
  im.hal.run_services();
  return im.report(false, double(mono_ns() - wall0) * 1e-9);
}

RunReport Executor::run_wall_clock(const RunLimits& limits, const WallClockOptions& options) {
  Impl& im = *impl_;
  im.reset();
  std::vector<std::string> notes;
  bool locked = false;
  if (options.lock_memory) {
    if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
      locked = true;
      notes.push_back("memory locked (mlockall)");
    } else {
      notes.push_back(std::string("memory not locked: mlockall: ") + std::strerror(errno));
    }
  }
  std::vector<std::string> rt_notes;  // written by the servo thread before its loop
  std::atomic<bool> done{false};
  const int64_t wall0 = mono_ns();

  std::thread servo([&] {
    if (options.cpu >= 0) {
      cpu_set_t set;
      CPU_ZERO(&set);
      CPU_SET(options.cpu, &set);
      int rc = pthread_setaffinity_np(pthread_self(), sizeof set, &set);
      rt_notes.push_back(rc == 0 ? "servo thread pinned to CPU " + std::to_string(options.cpu)
                                 : "not pinned to CPU " + std::to_string(options.cpu) + ": " +
                                       std::strerror(rc));
    }
    if (options.fifo_priority > 0) {
      sched_param sp{};
      sp.sched_priority = std::clamp(options.fifo_priority, sched_get_priority_min(SCHED_FIFO),
                                     sched_get_priority_max(SCHED_FIFO));
      int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp);
      rt_notes.push_back(rc == 0 ? "SCHED_FIFO priority " + std::to_string(sp.sched_priority)
                                 : "SCHED_FIFO not granted (" + std::string(std::strerror(rc)) +
                                       "): running with normal scheduling");
    } else {
      rt_notes.push_back("normal scheduling (SCHED_OTHER)");
    }
    if (options.spin_ns > 0)
      rt_notes.push_back("busy-waits the last " + std::to_string(options.spin_ns / 1000) +
                         " us before each deadline");
    // Normal threads get 50 us of timer slack: wake-ups would come that late.
    prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0);
    prefault_stack();
    const int64_t start_ns = mono_ns() + 1'000'000;
    while (!im.finished(limits)) {
      Impl::Slot& s = im.slots[im.next_slot()];
      const int64_t deadline = start_ns + s.next_ns;
      if (options.spin_ns > 0) {
        if (mono_ns() < deadline - options.spin_ns) sleep_until_ns(deadline - options.spin_ns);
        while (mono_ns() < deadline) {
        }
      } else if (mono_ns() < deadline) {
        sleep_until_ns(deadline);
      }
      const int64_t woke = mono_ns();
      s.stats->latency.add(woke - deadline);
      im.run_cycle(s, limits);
      if (mono_ns() > deadline + s.thread->period_ns) im.count_overrun(s);
      if (im.hal.stop_requested()) break;
    }
    done.store(true, std::memory_order_release);
  });

  const int64_t service_period = std::max<int64_t>(limits.service_period_ns, 100'000);
  // Background services (a field being read and checked) get a thread of
  // their own, so a long one never holds up the others, the planner's
  // refill among them. In simulated time they run with the others instead.
  std::thread background;
  if (im.hal.service_count(Hal::Services::kBackground) > 0)
    background = std::thread([&] {
      int64_t next_bg = mono_ns();
      while (!done.load(std::memory_order_acquire)) {
        im.hal.run_services(Hal::Services::kBackground);
        next_bg = std::max(next_bg + service_period, mono_ns());
        sleep_until_ns(next_bg);
      }
    });
  int64_t next = mono_ns();
  while (!done.load(std::memory_order_acquire)) {
    im.hal.run_services(Hal::Services::kForeground);
    if (limits.progress) limits.progress(limits.progress_user, mono_ns() - wall0);
    next += service_period;
    sleep_until_ns(next);
  }
  servo.join();
  if (background.joinable()) background.join();
  im.hal.run_services();
  if (locked) munlockall();
  RunReport r = im.report(true, double(mono_ns() - wall0) * 1e-9);
  r.notes = notes;
  r.notes.insert(r.notes.end(), rt_notes.begin(), rt_notes.end());
  return r;
}

}  // namespace truecut::rt::hal
