#include "run_support.hpp"

#include <signal.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace truecut::cli {
namespace {

rt::hal::Hal* g_running_hal = nullptr;
volatile std::sig_atomic_t g_interrupted = 0;
void on_sigint(int) {
  g_interrupted = 1;
  if (g_running_hal) g_running_hal->request_stop();
}

}  // namespace

std::vector<std::filesystem::path> component_path(const ParsedArgs& a) {
  std::vector<std::filesystem::path> path;
  for (const auto& d : a.values("component-path"))
    path.emplace_back(d);
  if (const char* env = std::getenv("TRUECUT_COMPONENT_PATH")) {
    std::string s = env, cur;
    for (char c : s + ":") {
      if (c != ':') {
        cur += c;
      } else if (!cur.empty()) {
        path.emplace_back(cur);
        cur.clear();
      }
    }
  }
  std::error_code ec;
  auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    path.push_back(exe.parent_path() / "components");
    path.push_back(exe.parent_path().parent_path() / "lib" / "truecut" / "components");
  }
  return path;
}

void print_progress(void* user, int64_t t_ns) {
  auto& p = *static_cast<Progress*>(user);
  if (p.last_ns >= 0 && t_ns - p.last_ns < 1'000'000'000) return;  // at most once per second
  p.last_ns = t_ns;
  if (p.total_ns > 0)
    std::fprintf(stderr, "\r  %.1f / %.1f s (%3.0f%%)", t_ns * 1e-9, p.total_ns * 1e-9,
                 100.0 * double(t_ns) / double(p.total_ns));
  else
    std::fprintf(stderr, "\r  %.1f s", t_ns * 1e-9);
}

InterruptibleRun run_interruptible(rt::hal::Hal& h, const rt::hal::RunLimits& limits,
                                   bool wall_clock, const rt::hal::WallClockOptions& wall) {
  rt::hal::Executor exec(h);
  g_interrupted = 0;
  g_running_hal = &h;
  // sigaction, not std::signal: the cleanup handler comes back as it was
  // installed (its mask of the three signals, rt/interrupt_cleanup.hpp).
  struct sigaction stop {
  }, previous{};
  stop.sa_handler = on_sigint;
  sigemptyset(&stop.sa_mask);
  sigaction(SIGINT, &stop, &previous);
  rt::hal::RunReport r =
      wall_clock ? exec.run_wall_clock(limits, wall) : exec.run_simulated(limits);
  sigaction(SIGINT, &previous, nullptr);
  g_running_hal = nullptr;
  return {r, g_interrupted != 0};
}

}  // namespace truecut::cli
