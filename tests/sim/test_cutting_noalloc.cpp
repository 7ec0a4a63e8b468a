// DexelModel::cut allocates nothing (nor the force model, nor the cutting
// component's servo function).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "alloc_counter.hpp"
#include "test_paths.hpp"
#include "truecut/rt/executor.hpp"
#include "truecut/rt/hal_file.hpp"
#include "truecut/sim/benchmark_parts.hpp"
#include "truecut/sim/cutting/cutting_force.hpp"
#include "truecut/sim/cutting/dexel_model.hpp"

using namespace truecut::sim;
using namespace truecut::sim::cutting;
using namespace truecut::test;

TEST(CuttingNoAlloc, CounterSeesAllocations) {
  EXPECT_EQ(2u, alloc_counter_self_test());
}

// With helper threads (threads = 2) the caller hands each large instance
// over with atomics and a futex wake: no allocation, no lock either.
class CuttingNoAllocThreads : public ::testing::TestWithParam<int> {};

TEST_P(CuttingNoAllocThreads, CutAllocatesNothing) {
  truecut::offline::TriangleMesh plane;
  const int n = 40;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      plane.vertices_mm.emplace_back(i * 0.5, j * 0.5, 0.0);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const auto a = std::uint32_t(j * (n + 1) + i), b = a + 1, c = a + n + 2, d = a + n + 1;
      plane.triangles.push_back({a, b, c});
      plane.triangles.push_back({a, c, d});
    }
  const std::vector<int> ids(plane.triangles.size(), 1);
  const std::vector<StockBox> stock{{{0, 0, -5}, {20, 20, 1}}};
  DexelOptions o;
  o.threads = GetParam();
  DexelModel m = DexelModel::build(plane, ids, stock, o);
  const CutterShape shapes[3] = {{3, 0, 10}, {3, 3, 10}, {3, 1, 10}};
  double removed = 0;
  reset_alloc_counter();
  arm_alloc_counter();
  CutterPose prev{{-4, 2, 0.5}, {0, 0, 1}};
  for (int k = 0; k < 3000; ++k) {
    const double t = k * 1e-3;
    CutterPose pose{{-4 + 8 * t, 2 + 5 * std::sin(t), 0.5 - 0.05 * t},
                    Eigen::Vector3d(0.2 * std::sin(3 * t), 0.1, 1).normalized()};
    const Engagement e = m.cut(shapes[k % 3], prev, pose, false);
    removed += cutting_load(e, 1e-3, 3, 12000, ForceModel{}).mrr_mm3_per_s;
    prev = pose;
  }
  disarm_alloc_counter();
  EXPECT_EQ(RtViolations{}, armed_violations());
  EXPECT_GT(removed, 0.0);
  EXPECT_GT(m.removed_total_mm3(), 10.0);
  if (GetParam() > 1) {
    EXPECT_GT(m.thread_stats().jobs, 100u) << "instances were shared";
  }
}

INSTANTIATE_TEST_SUITE_P(Threads, CuttingNoAllocThreads, ::testing::Values(1, 2),
                         [](const auto& info) { return "Threads" + std::to_string(info.param); });

TEST(CuttingNoAlloc, ComponentServoCyclesAllocateNothing) {
  const auto dir = scratch_dir();
  const auto part = make_part(PartId::kImplant, {2.0, 0.8, 1.0, 2.0});
  write_part(part, dir / "implant");
  truecut::rt::hal::HalOptions o;
  o.component_path = {component_dir()};
  o.output_dir = dir;
  truecut::rt::hal::Hal hal(o);
  // The tool sweeps across the shaft top (siggen triangle, ±6 mm at 2 Hz).
  truecut::rt::hal::load_hal_text(
      hal,
      "loadrt threads name1=servo period1=1000000\nloadrt siggen names=p\n"
      "loadrt cutting threads=2 nominal=" +
          (dir / "implant/nominal.stl").string() + " part=" + (dir / "implant/part.json").string() +
          "\nsetp p.amplitude 6\nsetp p.frequency 2\nsetp cutting.0.tcp-z 17\n"
          "setp cutting.0.tool-radius 2\nsetp cutting.0.tool-corner-radius 0.5\n"
          "setp cutting.0.tool-flute-length 20\nsetp cutting.0.spindle-rpm 12000\n"
          "setp cutting.0.enable 1\nnet x p.triangle => cutting.0.tcp-x\n"
          "addf p.update servo\naddf cutting.0.update servo\n",
      "cut.hal");
  truecut::rt::hal::Executor ex(hal);
  truecut::rt::hal::RunLimits lim;
  lim.max_cycles = 2000;
  lim.cycle_probe = alloc_counting_probe;
  reset_alloc_counter();
  const auto r = ex.run_simulated(lim);
  EXPECT_EQ(2000u, r.threads[0].cycles);
  EXPECT_EQ(RtViolations{}, armed_violations());
  EXPECT_NEAR(1.6 * 1.6 * 0.3, hal.get_pin_or_param("cutting.0.removed-mm3").f, 0.01)
      << "the tool cut";
}
