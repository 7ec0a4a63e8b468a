// Latency test of the servo-thread executor, like LinuxCNC's latency-test:
// a trivial component chain (siggen -> 5 joint position loops -> recorder)
// runs in wall-clock mode with the servo thread pinned to one CPU under
// SCHED_FIFO (when permitted) while another thread loads the other CPU.
// Prints per-cycle compute time and wake-up latency percentiles.
//
//   servo_latency [--seconds S] [--servo-cpu N] [--load-cpu N] [--no-load]
#include <pthread.h>
#include <sched.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "truecut/rt/executor.hpp"
#include "truecut/rt/hal_file.hpp"

using namespace truecut::rt::hal;

namespace {

std::string chain(long period_ns) {
  std::string s = "newthread servo-thread " + std::to_string(period_ns) + "\n";
  s += "loadrt siggen names=path\nloadrt pos_loop names=x,y,z,a,c\n";
  s += "loadrt recorder file=/dev/null columns=x,y,z,a,c\n";
  s += "setp path.amplitude 50\n";
  for (const char* j : {"x", "y", "z", "a", "c"}) {
    s += std::string("net cmd path.sine => ") + j + ".pos-cmd\n";
    s += std::string("net ") + j + "-fb " + j + ".pos-fb => recorder.0." + j + "\n";
  }
  s += "addf path.update servo-thread\n";
  for (const char* j : {"x", "y", "z", "a", "c"})
    s += std::string("addf ") + j + ".update servo-thread\n";
  s += "addf recorder.0.sample servo-thread\n";
  return s;
}

// Keeps a CPU busy with arithmetic and memory traffic until stopped.
void load_cpu(int cpu, std::atomic<bool>& stop) {
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  pthread_setaffinity_np(pthread_self(), sizeof set, &set);
  std::vector<double> buf(4 << 20, 1.0);  // 32 MiB, larger than the caches
  size_t i = 0;
  double acc = 0;
  while (!stop.load(std::memory_order_relaxed)) {
    for (int k = 0; k < 4096; ++k, i = (i + 4099) % buf.size())
      acc += buf[i] * 1.0000001;
    buf[i % buf.size()] = acc;
  }
}

void print_row(const char* what, const truecut::rt::DurationHistogram& h) {
  std::printf("    %-8s median %8.2f us  p99 %8.2f us  p99.99 %8.2f us  max %8.2f us\n", what,
              h.percentile_ns(0.5) * 1e-3, h.percentile_ns(0.99) * 1e-3,
              h.percentile_ns(0.9999) * 1e-3, h.max_ns() * 1e-3);
}

}  // namespace

int main(int argc, char** argv) {
  double seconds = 10;
  int servo_cpu = 1, load_cpu_id = 0;
  bool load = true;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "--seconds" && i + 1 < argc)
      seconds = std::atof(argv[++i]);
    else if (a == "--servo-cpu" && i + 1 < argc)
      servo_cpu = std::atoi(argv[++i]);
    else if (a == "--load-cpu" && i + 1 < argc)
      load_cpu_id = std::atoi(argv[++i]);
    else if (a == "--no-load")
      load = false;
    else {
      std::fprintf(
          stderr,
          "usage: servo_latency [--seconds S] [--servo-cpu N] [--load-cpu N] [--no-load]\n");
      return 2;
    }
  }
  std::printf("servo_latency: %u CPUs, servo thread on CPU %d, %s, %.0f s per period\n",
              std::thread::hardware_concurrency(), servo_cpu,
              load ? ("load on CPU " + std::to_string(load_cpu_id)).c_str() : "no load", seconds);
  std::atomic<bool> stop{false};
  std::thread loader;
  if (load) loader = std::thread(load_cpu, load_cpu_id, std::ref(stop));

  struct Case {
    long period_ns;
    long spin_ns;
  };
  for (Case c :
       {Case{1'000'000, 0}, Case{125'000, 0}, Case{1'000'000, 50'000}, Case{125'000, 50'000}}) {
    const long period_ns = c.period_ns;
    HalOptions opt;
    opt.component_path = {TRUECUT_COMPONENT_DIR};
    Hal hal(opt);
    load_hal_text(hal, chain(period_ns), "chain.hal");
    Executor ex(hal);
    RunLimits lim;
    lim.duration_ns = static_cast<int64_t>(seconds * 1e9);
    WallClockOptions w;
    w.cpu = servo_cpu;
    w.fifo_priority = 80;
    w.spin_ns = c.spin_ns;
    auto r = ex.run_wall_clock(lim, w);
    const auto& t = r.threads.at(0);
    std::printf("\nperiod %ld us, %s: %llu cycles, %llu overruns\n", period_ns / 1000,
                c.spin_ns ? ("sleep + " + std::to_string(c.spin_ns / 1000) + " us spin").c_str()
                          : "sleep only",
                (unsigned long long)t.cycles, (unsigned long long)t.overruns);
    for (const auto& n : r.notes)
      std::printf("    setup    %s\n", n.c_str());
    print_row("compute", t.compute);
    print_row("latency", t.latency);
    std::printf("    compute as share of the period: median %.3f %%, max %.2f %%\n",
                100.0 * t.compute.percentile_ns(0.5) / period_ns,
                100.0 * t.compute.max_ns() / period_ns);
  }
  stop = true;
  if (loader.joinable()) loader.join();
  return 0;
}
