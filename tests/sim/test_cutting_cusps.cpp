// The machined mesh between dexels: the cusps a ball leaves between passes
// are put where the swept surfaces of neighbouring dexels meet, so the mesh
// the CMM probes follows the exact cut to far better than the dexel spacing
// alone would allow. The reference is exact: a second dexel model holding
// one dexel at each probe point, along its probing normal, cut by the same
// sweeps.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <utility>
#include <vector>

#include "cutting_test_meshes.hpp"
#include "truecut/sim/cutting/dexel_model.hpp"
#include "truecut/sim/measure/cmm.hpp"

using namespace truecut::sim;
using namespace truecut::sim::cutting;
using truecut::offline::TriangleMesh;
using truecut::sim::test::grid;

namespace {

// The surface under test at 0.3 mm dexels and the exact reference at the
// probe points, cut by the same sweeps.
class CuspFixture {
 public:
  CuspFixture(const TriangleMesh& surface, std::vector<StockBox> stock,
              std::vector<measure::CmmPoint> points)
      : points_(std::move(points)) {
    DexelOptions o;
    o.spacing_mm = 0.3;
    model_ = DexelModel::build(surface, std::vector<int>(surface.triangles.size(), 1), stock, o);
    // One tiny triangle per probe point, its first corner on the point and
    // its normal the probing direction: one dexel exactly there.
    TriangleMesh tiny;
    for (const auto& p : points_) {
      const Eigen::Vector3d u = p.normal.unitOrthogonal(), v = p.normal.cross(u);
      const auto base = static_cast<std::uint32_t>(tiny.vertices_mm.size());
      tiny.vertices_mm.push_back(p.position_mm);
      tiny.vertices_mm.push_back(p.position_mm + 1e-6 * u);
      tiny.vertices_mm.push_back(p.position_mm + 1e-6 * v);
      tiny.triangles.push_back({base, base + 1, base + 2});
    }
    DexelOptions r;
    r.spacing_mm = 1.0;
    r.cell_mm = 0.5;
    reference_ = DexelModel::build(tiny, std::vector<int>(tiny.triangles.size(), 1), stock, r);
    for (std::size_t i = 0; i < points_.size(); ++i) {
      EXPECT_EQ(points_[i].position_mm, reference_.position(3 * i));
      EXPECT_NEAR(1.0, reference_.normal(3 * i).dot(points_[i].normal), 1e-12);
    }
  }

  void cut(const CutterShape& shape, const CutterPose& from, const CutterPose& to) {
    model_.cut(shape, from, to);
    reference_.cut(shape, from, to);
  }

  // Largest |machined mesh probed along the normal − exact surface| (mm),
  // and the range of the exact surface.
  double max_error_mm(double* relief_mm = nullptr) const {
    measure::CmmOptions o;
    o.sigma_mm = 0;
    const auto probed = measure::probe(model_.machined_mesh(), points_, o);
    double worst = 0, lo = 1e9, hi = -1e9;
    for (std::size_t i = 0; i < points_.size(); ++i) {
      EXPECT_TRUE(probed[i].valid) << i;
      const double exact = reference_.height_mm(3 * i);
      lo = std::min(lo, exact);
      hi = std::max(hi, exact);
      worst = std::max(worst, std::abs(probed[i].deviation_mm - exact));
    }
    if (relief_mm) *relief_mm = hi - lo;
    return worst;
  }

  const DexelModel& model() const { return model_; }

 private:
  std::vector<measure::CmmPoint> points_;
  DexelModel model_, reference_;
};

// Probe points on lines across the passes: origin + a·u + b·v for the given
// a and b from b0 to b1 in steps of db, normal n.
std::vector<measure::CmmPoint> lines_across(const Eigen::Vector3d& origin, const Eigen::Vector3d& u,
                                            const Eigen::Vector3d& v, const Eigen::Vector3d& n,
                                            std::vector<double> along, double b0, double b1,
                                            double db) {
  std::vector<measure::CmmPoint> pts;
  for (double a : along)
    for (double b = b0; b <= b1; b += db)
      pts.push_back({origin + a * u + b * v, n, 1});
  return pts;
}

const Eigen::Vector3d kUnitX = Eigen::Vector3d::UnitX(), kUnitY = Eigen::Vector3d::UnitY(),
                      kUnitZ = Eigen::Vector3d::UnitZ();

}  // namespace

// A Ø6 ball raster at 1 mm stepover (41.9 µm scallops) on a plate of 0.5 mm
// cells, 0.3 mm dexels (rows 0.167 mm apart), the cusps off the rows: a
// straight edge across a cusp would read up to ~10 µm low.
TEST(CuttingCusps, BallRasterCuspsFollowTheExactCut) {
  CuspFixture f(
      grid({0, 0, 0}, kUnitX, kUnitY, 80, 40, 0.5), {{{0, 0, -5}, {40, 20, 2}}},
      lines_across({0, 0, 0}, kUnitX, kUnitY, kUnitZ, {12.13, 15.41, 19.77}, 5, 15, 0.013));
  const CutterShape ball{3, 3, 12};
  for (int k = 3; k <= 17; ++k) {
    const double y = 0.07 + k;
    f.cut(ball, {{8, y, 0.3}, kUnitZ}, {{24, y, 0.3}, kUnitZ});
  }
  double relief = 0;
  const double err = f.max_error_mm(&relief);
  std::printf("ball raster: scallop %.2f um, mesh within %.2f um of the exact cut\n", relief * 1e3,
              err * 1e3);
  EXPECT_NEAR(0.0419, relief, 1e-3);
  EXPECT_LT(err, 2e-3);  // sag of a 0.167 mm chord on R3: 1.16 µm

  // No crack: every edge of the mesh is shared by two triangles except on the
  // plate's border.
  const TriangleMesh out = f.model().machined_mesh();
  EXPECT_GT(out.vertices_mm.size(), f.model().size()) << "cusp vertices added";
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> edges;
  for (const auto& t : out.triangles)
    for (int k = 0; k < 3; ++k)
      ++edges[std::minmax(t[k], t[(k + 1) % 3])];
  auto on_border = [&](std::uint32_t v) {
    const Eigen::Vector3d& p = out.vertices_mm[v];
    return std::abs(p.x()) < 1e-9 || std::abs(p.x() - 40) < 1e-9 || std::abs(p.y()) < 1e-9 ||
           std::abs(p.y() - 20) < 1e-9;
  };
  for (const auto& [e, count] : edges) {
    ASSERT_LE(count, 2);
    if (count == 1) {
      ASSERT_TRUE(on_border(e.first) && on_border(e.second));
    }
  }
}

// The ball tilted 30° across the passes (the free-form's 5-axis side tilt).
TEST(CuttingCusps, TiltedBallRasterCuspsFollowTheExactCut) {
  CuspFixture f(grid({0, 0, 0}, kUnitX, kUnitY, 80, 40, 0.5), {{{0, 0, -5}, {40, 20, 2}}},
                lines_across({0, 0, 0}, kUnitX, kUnitY, kUnitZ, {12.13, 19.41}, 5, 15, 0.013));
  const CutterShape ball{3, 3, 12};
  const Eigen::Vector3d axis(0, std::sin(std::numbers::pi / 6), std::cos(std::numbers::pi / 6));
  for (int k = 3; k <= 17; ++k) {
    const double y = 0.07 + k;
    const Eigen::Vector3d centre_start(8, y, 3.3), centre_end(24, y, 3.3);
    f.cut(ball, {centre_start - 3 * axis, axis}, {centre_end - 3 * axis, axis});
  }
  const double err = f.max_error_mm();
  std::printf("tilted ball raster: mesh within %.2f um of the exact cut\n", err * 1e3);
  EXPECT_LT(err, 2e-3);
}

// A steep face (normal 10° above horizontal, as the dome near its equator)
// cut by a vertical ball in horizontal passes 1 mm apart along the face:
// each cusp lies between the ball of one pass and the flank of the next.
TEST(CuttingCusps, CuspsBetweenBallAndFlankOnASteepFace) {
  const double tilt = 10 * std::numbers::pi / 180;
  const Eigen::Vector3d n(0, std::cos(tilt), std::sin(tilt)), v = n.cross(kUnitX);
  CuspFixture f(grid({0, 0, 0}, kUnitX, v, 80, 40, 0.5), {{{-5, -20, -30}, {45, 10, 30}}},
                lines_across({0, 0, 0}, kUnitX, v, n, {12.13, 19.41}, 5, 15, 0.013));
  const CutterShape ball{3, 3, 12};
  for (int k = 3; k <= 17; ++k) {
    const double b = 0.37 + k;  // the contact point, along the face
    const Eigen::Vector3d centre = b * v + 3 * n;
    f.cut(ball, {centre + Eigen::Vector3d(8, 0, -3), kUnitZ},
          {centre + Eigen::Vector3d(24, 0, -3), kUnitZ});
  }
  double relief = 0;
  const double err = f.max_error_mm(&relief);
  std::printf("steep face: relief %.2f um, mesh within %.2f um of the exact cut\n", relief * 1e3,
              err * 1e3);
  EXPECT_GT(relief, 0.02);
  EXPECT_LT(err, 2e-3);
}
