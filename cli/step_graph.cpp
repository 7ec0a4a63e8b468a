#include "step_graph.hpp"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <thread>

namespace truecut::cli {

std::size_t StepGraph::add(GraphStep step) {
  for (std::size_t need : step.needs)
    if (need >= steps_.size())
      throw std::logic_error("step '" + step.label + "' needs a step added after it");
  steps_.push_back(std::move(step));
  succeeded_.push_back(0);
  return steps_.size() - 1;
}

void StepGraph::run(std::size_t workers) {
  const std::size_t n = steps_.size();
  // The longest chain of costs from each step to the end: steps are added
  // after the steps they need, so one pass from the back suffices.
  std::vector<double> chain(n, 0);
  for (std::size_t i = n; i-- > 0;) {
    if (succeeded_[i]) continue;
    chain[i] += steps_[i].cost;
    for (std::size_t need : steps_[i].needs)
      chain[need] = std::max(chain[need], chain[i]);
  }
  enum class State { waiting, running, succeeded, failed };
  std::vector<State> state(n, State::waiting);
  for (std::size_t i = 0; i < n; ++i)
    if (succeeded_[i]) state[i] = State::succeeded;
  std::vector<std::exception_ptr> failures(n);
  std::mutex mutex;
  std::condition_variable changed;
  std::size_t running = 0;
  bool failed = false;
  if (started_ == 0) start_ = std::chrono::steady_clock::now();

  auto next_ready = [&]() -> std::size_t {
    std::size_t best = n;
    for (std::size_t i = 0; i < n; ++i) {
      if (state[i] != State::waiting) continue;
      const bool ready = std::all_of(steps_[i].needs.begin(), steps_[i].needs.end(),
                                     [&](std::size_t k) { return state[k] == State::succeeded; });
      if (ready && (best == n || chain[i] > chain[best])) best = i;
    }
    return best;
  };
  auto worker = [&] {
    std::unique_lock<std::mutex> lock(mutex);
    while (true) {
      std::size_t i = n;
      changed.wait(lock, [&] {
        if (failed) return true;
        i = next_ready();
        return i != n || running == 0;
      });
      if (failed || i == n) {
        changed.notify_all();
        return;
      }
      state[i] = State::running;
      ++running;
      const std::size_t number = ++started_;
      if (show_progress_)
        std::fprintf(stderr, "demo [%zu/%zu] %s\n", number, n, steps_[i].label.c_str());
      lock.unlock();
      const auto step_start = std::chrono::steady_clock::now();
      std::exception_ptr failure;
      try {
        steps_[i].run();
      } catch (...) {
        failure = std::current_exception();
      }
      const auto now = std::chrono::steady_clock::now();
      lock.lock();
      --running;
      ++ended_;
      if (failure) {
        state[i] = State::failed;
        failures[i] = failure;
        failed = true;
      } else {
        state[i] = State::succeeded;
        succeeded_[i] = 1;
        if (show_progress_)
          std::fprintf(stderr, "demo [%zu/%zu] %s: done in %.1f s (%zu of %zu done, %.0f s)\n",
                       number, n, steps_[i].label.c_str(),
                       std::chrono::duration<double>(now - step_start).count(), ended_, n,
                       std::chrono::duration<double>(now - start_).count());
      }
      changed.notify_all();
    }
  };
  std::vector<std::thread> threads;
  for (std::size_t t = 1; t < std::max<std::size_t>(1, workers); ++t)
    threads.emplace_back(worker);
  worker();
  for (auto& t : threads)
    t.join();
  for (const auto& f : failures)
    if (f) std::rethrow_exception(f);
}

}  // namespace truecut::cli
