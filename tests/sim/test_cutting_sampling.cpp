// Material removal sampled by swept distance (SweptCut) against the exact
// groove a cutter leaves along an arc, computed here from the geometry of a
// ball and a flat end mill (not from the dexel model), and against a cut at
// every cycle; the instances it saves; the motion it keeps pending.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "cutting_test_meshes.hpp"
#include "truecut/sim/cutting/dexel_model.hpp"
#include "truecut/sim/cutting/swept_cut.hpp"

using namespace truecut::sim;
using namespace truecut::sim::cutting;
using truecut::sim::test::grid;

namespace {

// The top face z = 0 of a plate [0, 40] × [0, 20], 2 mm of stock on it.
DexelModel plate() {
  const auto mesh =
      grid({0, 0, 0}, Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), 80, 40, 0.5);
  const std::vector<int> ids(mesh.triangles.size(), 1);
  const std::vector<StockBox> stock{{{0, 0, -5}, {40, 20, 2}}};
  return DexelModel::build(mesh, ids, stock, {});
}

// The tool path: an arc of radius 10 mm about (20, 0) from 30° to 150°, the
// tip at height z, at 10 mm/s sampled by a 1 kHz servo (10 µm per cycle).
constexpr double kArcRadius = 10, kFrom = std::numbers::pi / 6, kTo = 5 * std::numbers::pi / 6;
constexpr double kStepMm = 0.01;
const Eigen::Vector2d kCentre(20, 0);

std::vector<CutterPose> arc(double z) {
  const int n = static_cast<int>(std::ceil(kArcRadius * (kTo - kFrom) / kStepMm));
  std::vector<CutterPose> poses;
  for (int k = 0; k <= n; ++k) {
    const double t = kFrom + (kTo - kFrom) * k / n;
    poses.push_back(
        {{kCentre.x() + kArcRadius * std::cos(t), kCentre.y() + kArcRadius * std::sin(t), z},
         Eigen::Vector3d::UnitZ()});
  }
  return poses;
}

// The exact height left at (x, y) by the tool swept along the arc; NaN where
// it is not compared: near the arc's ends, where the groove's wall is steeper
// than 45° (a sampling error normal to the surface grows along the dexel by
// 1/cos of the slope), and within 50 µm of a flat end mill's rim (a sharp
// edge leaves slivers between instances, docs/cutting.md).
double exact_height(const Eigen::Vector3d& p, const CutterShape& tool, double tip_z) {
  const Eigen::Vector2d d = p.head<2>() - kCentre;
  const double angle = std::atan2(d.y(), d.x());
  const double margin = 1.5 * tool.radius_mm / kArcRadius;
  if (angle < kFrom + margin || angle > kTo - margin) return std::nan("");
  const double rho = std::abs(d.norm() - kArcRadius);  // distance from the path
  const double r = tool.corner_radius_mm;
  if (r == 0) return rho < tool.radius_mm - 0.05 ? tip_z : std::nan("");
  if (rho <= tool.radius_mm - r) return tip_z;  // under the flat part of the end
  const double off = rho - (tool.radius_mm - r);
  if (off > r * std::sqrt(0.5)) return std::nan("");
  return std::min(2.0, tip_z + r - std::sqrt(r * r - off * off));
}

struct Run {
  DexelModel model = plate();
  std::uint64_t instances = 0;
};

// Replays the path through a sampler (CycleCut or SweptCut), then finish().
template <class Sampler>
Run replay(const CutterShape& tool, const std::vector<CutterPose>& path) {
  Run r;
  Sampler sampler;
  for (const auto& pose : path) {
    const Engagement e = sampler.step(r.model, tool, pose);
    r.instances += e.substeps;
    EXPECT_FALSE(e.invalid_input);
  }
  r.instances += sampler.finish(r.model).substeps;
  return r;
}

// Both samplings leave the exact groove within the model's sweep tolerance
// (DexelOptions::tolerance_mm, 1 µm) plus the dexel's own resolution on a
// curved floor, and the swept sampling places at most one instance per
// lateral step minus one cycle's motion.
void check_groove(const CutterShape& tool, double tip_z, double lateral_step_mm) {
  const auto path = arc(tip_z);
  const Run a = replay<CycleCut>(tool, path);
  const Run b = replay<SweptCut>(tool, path);
  const double tol = DexelOptions{}.tolerance_mm;
  int checked = 0;
  double worst_vs_cycle = 0;
  for (std::size_t i = 0; i < a.model.size(); ++i) {
    const double want = exact_height(a.model.position(i), tool, tip_z);
    if (std::isnan(want)) continue;
    ++checked;
    ASSERT_NEAR(want, a.model.height_mm(i), tol)
        << "per cycle at " << a.model.position(i).transpose();
    ASSERT_NEAR(want, b.model.height_mm(i), tol) << "swept at " << b.model.position(i).transpose();
    worst_vs_cycle =
        std::max(worst_vs_cycle, std::abs(a.model.height_mm(i) - b.model.height_mm(i)));
  }
  EXPECT_GT(checked, 10000);
  EXPECT_LE(worst_vs_cycle, tol);
  const double length = kArcRadius * (kTo - kFrom);
  const double most = std::ceil(length / (lateral_step_mm - kStepMm)) + 3;
  EXPECT_LE(double(b.instances), most) << "per cycle: " << a.instances;
  EXPECT_EQ(path.size() + 1, a.instances);  // DexelModel::cut(p, p) at the start tests p twice
  EXPECT_NEAR(a.model.removed_total_mm3(), b.model.removed_total_mm3(),
              tol * 2 * tool.radius_mm * length);
}

}  // namespace

TEST(CuttingSampling, BallEndMillGrooveIsExactWithAFractionOfTheInstances) {
  // Lateral instance spacing of a ball of radius 3 at 1 µm: ½·√(8·3·0.001).
  check_groove({3, 3, 10}, 0.5, 0.5 * std::sqrt(8 * 3 * 1e-3));
}

TEST(CuttingSampling, FlatEndMillGrooveIsExactWithAFractionOfTheInstances) {
  check_groove({2, 0, 10}, 1.0, 0.5 * std::sqrt(8 * 2 * 1e-3));
}

TEST(CuttingSampling, PendingMotionIsCutByFinish) {
  DexelModel m = plate();
  SweptCut s;
  const CutterShape ball{3, 3, 10};
  s.step(m, ball, {{10, 10, 0.5}, Eigen::Vector3d::UnitZ()});
  const double removed_at_start = m.removed_total_mm3();
  // 30 µm along x: within one instance spacing (77 µm), so nothing is cut.
  const Engagement e = s.step(m, ball, {{10.03, 10, 0.5}, Eigen::Vector3d::UnitZ()});
  EXPECT_EQ(0u, e.substeps);
  EXPECT_TRUE(s.pending());
  EXPECT_EQ(removed_at_start, m.removed_total_mm3());
  const Engagement f = s.finish(m);
  EXPECT_EQ(1u, f.substeps);
  EXPECT_GT(f.removed_mm3, 0.0);
  EXPECT_FALSE(s.pending());
  EXPECT_NEAR(removed_at_start + f.removed_mm3, m.removed_total_mm3(), 1e-12);
  EXPECT_EQ(0u, s.finish(m).substeps);  // nothing left
}

TEST(CuttingSampling, StandingStillCutsNothingAndLeavesNothingPending) {
  DexelModel m = plate();
  SweptCut s;
  const CutterPose here{{10, 10, 0.5}, Eigen::Vector3d::UnitZ()};
  EXPECT_EQ(1u, s.step(m, {3, 3, 10}, here).substeps);
  for (int k = 0; k < 10; ++k)
    EXPECT_EQ(0u, s.step(m, {3, 3, 10}, here).substeps);
  EXPECT_FALSE(s.pending());
}

TEST(CuttingSampling, ChangedToolCutsAtOnce) {
  DexelModel m = plate();
  SweptCut s;
  s.step(m, {3, 3, 10}, {{10, 10, 0.5}, Eigen::Vector3d::UnitZ()});
  const Engagement e = s.step(m, {3.5, 3.5, 10}, {{10.01, 10, 0.5}, Eigen::Vector3d::UnitZ()});
  EXPECT_EQ(1u, e.substeps);
  EXPECT_GT(e.removed_mm3, 0.0);
  EXPECT_FALSE(s.pending());
}

TEST(CuttingSampling, InvalidPoseCutsThePendingMotionAndStartsAfresh) {
  DexelModel m = plate();
  SweptCut s;
  const CutterShape ball{3, 3, 10};
  s.step(m, ball, {{10, 10, 0.5}, Eigen::Vector3d::UnitZ()});
  s.step(m, ball, {{10.03, 10, 0.5}, Eigen::Vector3d::UnitZ()});
  ASSERT_TRUE(s.pending());
  const Engagement bad = s.step(m, ball, {{std::nan(""), 10, 0.5}, Eigen::Vector3d::UnitZ()});
  EXPECT_TRUE(bad.invalid_input);
  EXPECT_EQ(1u, bad.substeps);
  EXPECT_GT(bad.removed_mm3, 0.0);
  EXPECT_FALSE(s.pending());
  // The next valid pose is a new start: its own instance, nothing between.
  const Engagement again = s.step(m, ball, {{30, 10, 0.5}, Eigen::Vector3d::UnitZ()});
  EXPECT_EQ(1u, again.substeps);
}

TEST(CuttingSampling, AMoveLongerThanAnInstanceSpacingIsCutInTheSameCycle) {
  DexelModel m = plate();
  SweptCut s;
  const CutterShape ball{3, 3, 10};
  s.step(m, ball, {{10, 10, 0.5}, Eigen::Vector3d::UnitZ()});
  const Engagement e = s.step(m, ball, {{11, 10, 0.5}, Eigen::Vector3d::UnitZ()});
  // 1 mm at 77 µm per instance: the same instances as DexelModel::cut.
  EXPECT_EQ(static_cast<std::uint32_t>(std::ceil(1.0 / (0.5 * std::sqrt(8 * 3 * 1e-3)))),
            e.substeps);
  EXPECT_FALSE(s.pending());
  EXPECT_EQ(1, s.cycles_covered());
}
