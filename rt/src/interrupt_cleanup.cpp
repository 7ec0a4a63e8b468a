#include "truecut/rt/interrupt_cleanup.hpp"

#include <signal.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <cstring>

namespace truecut::rt {
namespace {

enum SlotState : int { kFree = 0, kFilling = 1, kReady = 2 };

constexpr int kCleanupSignals[] = {SIGINT, SIGTERM, SIGHUP};

struct Slot {
  std::atomic<int> state{kFree};
  char path[kMaxPendingPathBytes];
};

std::array<Slot, kMaxPendingFiles> g_slots;

extern "C" void remove_pending_and_reraise(int sig) {
  const int saved_errno = errno;
  for (Slot& s : g_slots)
    if (s.state.load(std::memory_order_acquire) == kReady) ::unlink(s.path);
  errno = saved_errno;
  // Back to the default action only now that every file is gone, so the
  // signal ends the process with the status a shell expects (130 for
  // Ctrl-C). The raised signal stays pending until the handler returns (it
  // is blocked while the handler runs).
  ::signal(sig, SIG_DFL);
  ::raise(sig);
}

// The host of this thread's innermost PendingFilesToHost, when it has the calls.
thread_local const tc_hal_api_t* t_host_api = nullptr;
thread_local tc_hal_t* t_host_hal = nullptr;

bool has_pending_file_calls(const tc_hal_api_t* api) {
  return api != nullptr && TC_HAL_API_HAS(api, pending_file_done) &&
         api->pending_file_add != nullptr && api->pending_file_done != nullptr;
}

}  // namespace

PendingFilesToHost::PendingFilesToHost(const tc_hal_api_t* api, tc_hal_t* hal) noexcept
    : outer_api_(t_host_api), outer_hal_(t_host_hal) {
  const bool host = has_pending_file_calls(api);
  t_host_api = host ? api : nullptr;
  t_host_hal = host ? hal : nullptr;
}

PendingFilesToHost::~PendingFilesToHost() {
  t_host_api = outer_api_;
  t_host_hal = outer_hal_;
}

PendingFile::PendingFile(const std::filesystem::path& path) noexcept {
  const std::string& text = path.native();
  if (t_host_api != nullptr) {
    const int handle = t_host_api->pending_file_add(t_host_hal, text.c_str());
    if (handle >= 0) {
      slot_ = handle;
      host_ = t_host_api;
      host_hal_ = t_host_hal;
      return;
    }
  }
  if (text.size() + 1 > kMaxPendingPathBytes) return;
  for (std::size_t i = 0; i < g_slots.size(); ++i) {
    int expected = kFree;
    if (!g_slots[i].state.compare_exchange_strong(expected, kFilling, std::memory_order_acq_rel))
      continue;
    std::memcpy(g_slots[i].path, text.c_str(), text.size() + 1);
    g_slots[i].state.store(kReady, std::memory_order_release);
    slot_ = static_cast<int>(i);
    return;
  }
}

PendingFile::~PendingFile() {
  if (host_ != nullptr)
    host_->pending_file_done(host_hal_, slot_);
  else if (slot_ >= 0)
    g_slots[static_cast<std::size_t>(slot_)].state.store(kFree, std::memory_order_release);
}

void remove_pending_files_on_signals() {
  // No SA_RESETHAND: `timeout` and a shell's kill of a process group send
  // the same signal twice in quick succession, and with the default action
  // back on entry the second one, delivered to another thread, ended the
  // process before the handler had removed anything (a 1.46 GB
  // trace.csv.tmp was left once). A second signal now runs the handler too,
  // which removes the files again before it ends the process. The three
  // signals are blocked in the thread that runs the handler.
  struct sigaction sa {};
  sa.sa_handler = remove_pending_and_reraise;
  sigemptyset(&sa.sa_mask);
  for (const int sig : kCleanupSignals)
    sigaddset(&sa.sa_mask, sig);
  sa.sa_flags = 0;
  for (const int sig : kCleanupSignals)
    sigaction(sig, &sa, nullptr);
}

std::size_t pending_file_count() noexcept {
  std::size_t n = 0;
  for (const Slot& s : g_slots)
    n += s.state.load(std::memory_order_acquire) == kReady;
  return n;
}

}  // namespace truecut::rt
