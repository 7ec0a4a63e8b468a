// Google Benchmark: cost of one servo cycle of the trivial chain in
// simulated time (no sleeping), i.e. pure compute.
#include <benchmark/benchmark.h>

#include "truecut/rt/executor.hpp"
#include "truecut/rt/hal_file.hpp"

using namespace truecut::rt::hal;

static void BM_ServoCycle_SiggenFivePosLoops(benchmark::State& state) {
  HalOptions opt;
  opt.component_path = {TRUECUT_COMPONENT_DIR};
  Hal hal(opt);
  std::string s =
      "newthread servo-thread 1000000\nloadrt siggen names=path\n"
      "loadrt pos_loop names=x,y,z,a,c\n";
  for (const char* j : {"x", "y", "z", "a", "c"})
    s += std::string("net cmd path.sine => ") + j + ".pos-cmd\n";
  s += "addf path.update servo-thread\n";
  for (const char* j : {"x", "y", "z", "a", "c"})
    s += std::string("addf ") + j + ".update servo-thread\n";
  load_hal_text(hal, s, "chain.hal");
  Executor ex(hal);
  for (auto _ : state)
    ex.step();
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_ServoCycle_SiggenFivePosLoops);

BENCHMARK_MAIN();
