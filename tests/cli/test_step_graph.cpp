// The demo's step graph (cli/step_graph.hpp): a step starts only after the
// steps it needs succeeded, at most `workers` run at once, the longest
// remaining chain goes first, and a failure stops what depends on it.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <stdexcept>
#include <vector>

#include "step_graph.hpp"

namespace truecut::cli {
namespace {

// Records the order in which steps start and end, and how many ran at once.
struct Journal {
  std::mutex mutex;
  std::vector<std::size_t> started, ended;
  int running = 0, most_at_once = 0;

  std::function<void()> step(std::size_t id) {
    return [this, id] {
      {
        std::lock_guard<std::mutex> lock(mutex);
        started.push_back(id);
        most_at_once = std::max(most_at_once, ++running);
      }
      std::lock_guard<std::mutex> lock(mutex);
      --running;
      ended.push_back(id);
    };
  }
  std::size_t position(const std::vector<std::size_t>& v, std::size_t id) {
    return static_cast<std::size_t>(std::find(v.begin(), v.end(), id) - v.begin());
  }
};

// A graph shaped like one part's demo: generate, two machine runs, a field
// from both, then three routes of which one has a second iteration.
StepGraph demo_shaped(Journal& j) {
  StepGraph g;
  const auto gen = g.add({"generate", {}, 0.5, j.step(0)});
  const auto ideal = g.add({"ideal", {gen}, 10, j.step(1)});
  const auto uncomp = g.add({"uncompensated", {gen}, 10, j.step(2)});
  const auto field = g.add({"field", {ideal, uncomp}, 3, j.step(3)});
  const auto realtime = g.add({"realtime", {field}, 10, j.step(4)});
  g.add({"rewrite", {field}, 10, j.step(5)});
  const auto field2 = g.add({"field 2", {realtime}, 3, j.step(6)});
  g.add({"realtime 2", {field2}, 10, j.step(7)});
  return g;
}

TEST(StepGraph, EveryStepRunsOnceAfterWhatItNeeds) {
  for (std::size_t workers : {1u, 2u, 3u, 8u}) {
    Journal j;
    StepGraph g = demo_shaped(j);
    g.run(workers);
    ASSERT_EQ(j.ended.size(), 8u) << workers;
    const std::vector<std::pair<std::size_t, std::size_t>> needs{{0, 1}, {0, 2}, {1, 3}, {2, 3},
                                                                 {3, 4}, {3, 5}, {4, 6}, {6, 7}};
    for (const auto& [before, after] : needs)
      EXPECT_LT(j.position(j.ended, before), j.position(j.started, after))
          << "step " << after << " started before step " << before << " ended (" << workers
          << " workers)";
    EXPECT_LE(j.most_at_once, static_cast<int>(workers));
  }
}

TEST(StepGraph, OneWorkerStartsTheLongestRemainingChainFirst) {
  Journal j;
  StepGraph g = demo_shaped(j);
  g.run(1);
  // After the field, the real-time route (23 to go) before the rewrite (10).
  EXPECT_LT(j.position(j.started, 4), j.position(j.started, 5));
  // Equal chains: the step added first.
  EXPECT_LT(j.position(j.started, 1), j.position(j.started, 2));
}

TEST(StepGraph, IndependentStepsRunAtOnce) {
  // Two steps that each wait until the other has started: they finish only
  // when run at once (with one worker the wait would never end, so it is
  // bounded by a flag the first step gives up on).
  std::mutex m;
  std::condition_variable cv;
  int arrived = 0;
  bool both = true;
  auto meet = [&] {
    std::unique_lock<std::mutex> lock(m);
    ++arrived;
    cv.notify_all();
    if (!cv.wait_for(lock, std::chrono::seconds(30), [&] { return arrived == 2; })) both = false;
  };
  StepGraph g;
  g.add({"a", {}, 1, meet});
  g.add({"b", {}, 1, meet});
  g.run(2);
  EXPECT_TRUE(both);
}

TEST(StepGraph, AFailureStopsItsDependentsAndIsRethrown) {
  Journal j;
  StepGraph g;
  const auto gen = g.add({"generate", {}, 1, j.step(0)});
  const auto bad = g.add({"bad", {gen}, 1, [] { throw std::runtime_error("step bad failed"); }});
  g.add({"after bad", {bad}, 1, j.step(2)});
  g.add({"independent", {}, 1, j.step(3)});
  try {
    g.run(1);
    FAIL() << "no failure";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "step bad failed");
  }
  EXPECT_EQ(j.position(j.started, 2), j.started.size()) << "a step that needs the failed one ran";
}

TEST(StepGraph, ASecondRunRunsOnlyTheNewSteps) {
  Journal j;
  StepGraph g;
  const auto gen = g.add({"generate", {}, 1, j.step(0)});
  g.run(2);
  g.add({"machine", {gen}, 1, j.step(1)});
  g.run(2);
  EXPECT_EQ(j.started, (std::vector<std::size_t>{0, 1}));
}

TEST(StepGraph, AStepCannotNeedALaterOne) {
  StepGraph g;
  EXPECT_THROW(g.add({"x", {0}, 1, [] {}}), std::logic_error);
}

}  // namespace
}  // namespace truecut::cli
