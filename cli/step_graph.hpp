// The demo's steps as a graph: a step starts once the steps it needs have
// succeeded, so independent ones (other parts, or one part's real-time,
// rewrite and adapted routes) run at once on the CPUs there are.
#pragma once

#include <chrono>
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace truecut::cli {

struct GraphStep {
  std::string label;               // progress lines: "benchmark004 machine (realtime)"
  std::vector<std::size_t> needs;  // indices of earlier steps
  double cost = 1;                 // relative; the longest remaining chain starts first
  std::function<void()> run;       // throws on failure
};

class StepGraph {
 public:
  // Returns the step's index. A step may only need steps added before it.
  std::size_t add(GraphStep step);
  std::size_t size() const { return steps_.size(); }

  // Whether run() prints its progress lines (default yes; the demo shows
  // them on a terminal only, and not with --quiet).
  void show_progress(bool shown) { show_progress_ = shown; }

  // Runs every step not run yet, at most `workers` at a time, and prints a
  // line on stderr when each starts and ends (show_progress). After a failure no step
  // starts; the running ones end, then the failure of the earliest-added
  // failed step is rethrown. Steps that need a failed one are not run.
  void run(std::size_t workers);

 private:
  std::vector<GraphStep> steps_;
  std::vector<char> succeeded_;
  // Over all runs, for the progress lines "[started/steps]".
  std::size_t started_ = 0, ended_ = 0;
  bool show_progress_ = true;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace truecut::cli
