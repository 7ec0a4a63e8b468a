#include "worker_pool.hpp"

#include <linux/futex.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <climits>

namespace truecut::sim::cutting::detail {

namespace {

constexpr std::uint64_t kField = (1u << 24) - 1;
// A worker polls this many times (about 0.3 ms: a pause is ~30 ns on the
// EPYC VM of docs/performance.md) for the next job before
// it sleeps: the cutting's instances come every few servo cycles.
constexpr int kSpinPolls = 1000;

std::uint64_t claim_word(std::uint32_t gen, std::uint32_t chunks, std::uint32_t next) {
  return (std::uint64_t(gen & 0xFFFF) << 48) | (std::uint64_t(chunks) << 24) | next;
}

inline void cpu_relax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#endif
}

void futex_wait(std::atomic<std::uint32_t>& word, std::uint32_t expected) {
  syscall(SYS_futex, reinterpret_cast<std::uint32_t*>(&word), FUTEX_WAIT_PRIVATE, expected, nullptr,
          nullptr, 0);
}

void futex_wake_all(std::atomic<std::uint32_t>& word) {
  syscall(SYS_futex, reinterpret_cast<std::uint32_t*>(&word), FUTEX_WAKE_PRIVATE, INT_MAX, nullptr,
          nullptr, 0);
}

}  // namespace

static_assert(std::atomic<std::uint32_t>::is_always_lock_free &&
                  sizeof(std::atomic<std::uint32_t>) == sizeof(std::uint32_t),
              "the futex word must be a plain 32-bit integer");

WorkerPool::WorkerPool(int threads) {
  for (int i = 1; i < threads; ++i)
    workers_.emplace_back([this, i] { worker_main(i); });
}

WorkerPool::~WorkerPool() {
  stop_.store(true, std::memory_order_seq_cst);
  gen_.fetch_add(1, std::memory_order_seq_cst);
  futex_wake_all(gen_);
  for (auto& t : workers_)
    t.join();
}

void WorkerPool::work(std::uint32_t gen, int thread) noexcept {
  std::uint64_t c = claim_.load(std::memory_order_acquire);
  for (;;) {
    if ((c >> 48) != (gen & 0xFFFF)) return;  // a later job: the caller has moved on
    const std::uint32_t chunks = static_cast<std::uint32_t>((c >> 24) & kField);
    const std::uint32_t next = static_cast<std::uint32_t>(c & kField);
    if (next >= chunks) return;
    // A successful claim holds the caller in run() until the chunk is done,
    // so fn_ and context_ stay those of this job while it runs.
    if (!claim_.compare_exchange_weak(c, c + 1, std::memory_order_acq_rel,
                                      std::memory_order_acquire))
      continue;
    fn_(context_, next, thread);
    if (thread != 0) worker_chunks_.fetch_add(1, std::memory_order_relaxed);
    done_.fetch_add(1, std::memory_order_release);
    c = claim_.load(std::memory_order_acquire);
  }
}

void WorkerPool::worker_main(int index) noexcept {
  std::uint32_t seen = 0;
  for (;;) {
    std::uint32_t g = gen_.load(std::memory_order_acquire);
    for (int i = 0; g == seen && i < kSpinPolls; ++i) {
      cpu_relax();
      g = gen_.load(std::memory_order_acquire);
    }
    while (g == seen) {
      sleepers_.fetch_add(1, std::memory_order_seq_cst);
      if (gen_.load(std::memory_order_seq_cst) == seen) futex_wait(gen_, seen);
      sleepers_.fetch_sub(1, std::memory_order_seq_cst);
      g = gen_.load(std::memory_order_acquire);
    }
    seen = g;
    if (stop_.load(std::memory_order_acquire)) return;
    work(g, index);
  }
}

void WorkerPool::run(std::uint32_t chunks, ChunkFn fn, void* context) noexcept {
  if (chunks == 0) return;
  if (workers_.empty() || chunks == 1) {
    for (std::uint32_t c = 0; c < chunks; ++c)
      fn(context, c, 0);
    return;
  }
  ++stats_.jobs;
  stats_.chunks += chunks;
  // Every chunk of the previous job is done (run() waited for them), so no
  // worker reads fn_ or context_ now.
  fn_ = fn;
  context_ = context;
  done_.store(0, std::memory_order_relaxed);
  ++generation_;
  claim_.store(claim_word(generation_, chunks, 0), std::memory_order_release);
  gen_.store(generation_, std::memory_order_seq_cst);
  if (sleepers_.load(std::memory_order_seq_cst) > 0) {
    futex_wake_all(gen_);
    ++stats_.wakes;
  }
  work(generation_, 0);
  while (done_.load(std::memory_order_acquire) < chunks) {
    cpu_relax();
    ++stats_.wait_spins;
  }
}

WorkerPool::Stats WorkerPool::stats() const noexcept {
  Stats s = stats_;
  s.worker_chunks = worker_chunks_.load(std::memory_order_relaxed);
  return s;
}

}  // namespace truecut::sim::cutting::detail
