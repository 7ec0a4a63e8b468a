// Helper threads for the cutting (internal to the cutting library): the
// calling thread and N − 1 workers share the chunks of one job, claimed one
// at a time from an atomic counter. No lock, no allocation per job: the
// caller publishes the job with two atomic stores (and a futex wake when a
// worker sleeps), works on chunks itself, and then waits only for the
// chunks a worker has already claimed. A worker that has not woken up yet
// claims nothing, so a slow or descheduled worker never holds the caller up
// longer than one chunk. Which thread runs a chunk does not change what the
// chunk computes; callers combine the chunks' results in chunk order.
#pragma once

#include <atomic>
#include <cstdint>
#include <thread>
#include <vector>

namespace truecut::sim::cutting::detail {

class WorkerPool {
 public:
  // Chunk function: run(context, chunk index, thread index in [0, threads)).
  using ChunkFn = void (*)(void* context, std::uint32_t chunk, int thread);

  // threads ≥ 1: the caller plus threads − 1 workers (started here).
  explicit WorkerPool(int threads);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  int threads() const noexcept { return static_cast<int>(workers_.size()) + 1; }
  // Runs fn(context, c, thread) for every c in [0, chunks) (chunks < 2^24)
  // and returns when all have finished. The caller is thread 0. Not
  // reentrant; one caller at a time. Allocates nothing.
  void run(std::uint32_t chunks, ChunkFn fn, void* context) noexcept;

  // Counters of the caller's side, for the benchmark and docs.
  struct Stats {
    std::uint64_t jobs = 0;           // run() calls with more than one chunk
    std::uint64_t chunks = 0;         // chunks in those jobs
    std::uint64_t worker_chunks = 0;  // of which the workers ran
    std::uint64_t wakes = 0;          // futex wake calls (a worker was asleep)
    std::uint64_t wait_spins = 0;     // caller's polls while a worker finished a chunk
  };
  Stats stats() const noexcept;

 private:
  void worker_main(int index) noexcept;
  // Claims and runs chunks of job `gen` until none is left.
  void work(std::uint32_t gen, int thread) noexcept;

  // claim_: job generation (16 bits) | chunk count (24) | next chunk (24).
  std::atomic<std::uint64_t> claim_{0};
  std::atomic<std::uint32_t> done_{0};      // chunks finished in the current job
  std::atomic<std::uint32_t> gen_{0};       // futex word: generation of the latest job
  std::atomic<std::uint32_t> sleepers_{0};  // workers in (or entering) futex wait
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> worker_chunks_{0};
  ChunkFn fn_ = nullptr;
  void* context_ = nullptr;
  std::uint32_t generation_ = 0;  // caller's side
  Stats stats_;
  std::vector<std::thread> workers_;
};

}  // namespace truecut::sim::cutting::detail
