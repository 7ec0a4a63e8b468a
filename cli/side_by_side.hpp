// Runs independent pieces of work on threads of their own and waits for
// all of them; a failure is rethrown after all have ended, the first in the
// order given (so which error a user sees does not depend on timing).
#pragma once

#include <exception>
#include <functional>
#include <future>
#include <vector>

namespace truecut::cli {

inline void run_side_by_side(const std::vector<std::function<void()>>& tasks) {
  std::vector<std::future<void>> running;
  running.reserve(tasks.size());
  for (const auto& task : tasks)
    running.push_back(std::async(std::launch::async, task));
  std::exception_ptr first;
  for (auto& r : running) {
    try {
      r.get();
    } catch (...) {
      if (!first) first = std::current_exception();
    }
  }
  if (first) std::rethrow_exception(first);
}

}  // namespace truecut::cli
