// The dexel cutting model: known cuts of flat, ball, bull-nose and tilted
// end mills leave the textbook surfaces; volumes, engagement and force.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <numbers>

#include "cutting_test_meshes.hpp"
#include "test_paths.hpp"
#include "truecut/sim/cutting/cutting_force.hpp"
#include "truecut/sim/cutting/dexel_model.hpp"

using namespace truecut::sim;
using namespace truecut::sim::cutting;
using truecut::offline::TriangleMesh;
using truecut::sim::test::grid;

namespace {

constexpr double kTol = 5e-3;  // the accuracy the model promises (mm)

// The top face z = 0 of a plate [0, 40] × [0, 20], stock up to z = 2.
struct Plate {
  TriangleMesh mesh =
      grid({0, 0, 0}, Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), 80, 40, 0.5);
  std::vector<int> ids = std::vector<int>(mesh.triangles.size(), 1);
  std::vector<StockBox> stock{{{0, 0, -5}, {40, 20, 2}}};
  DexelModel build(double spacing = 0.1) const {
    DexelOptions o;
    o.spacing_mm = spacing;
    return DexelModel::build(mesh, ids, stock, o);
  }
};

CutterPose at(double x, double y, double z, Eigen::Vector3d axis = Eigen::Vector3d::UnitZ()) {
  return {{x, y, z}, axis};
}

}  // namespace

TEST(Cutting, InitialHeightIsTheStockAllowance) {
  const DexelModel m = Plate{}.build();
  ASSERT_GT(m.size(), 80000u);
  double area = 0;
  for (std::size_t i = 0; i < m.size(); ++i) {
    area += m.area_mm2(i);
    ASSERT_DOUBLE_EQ(2.0, m.height_mm(i)) << i;
    ASSERT_NEAR(1.0, m.normal(i).z(), 1e-12);
  }
  EXPECT_NEAR(800.0, area, 1e-9);
}

// Issue 23: a nominal in µm (17 m across) grew past 2.8 GB before the dexel
// limit was reached. The plate (about 205,000 dexels at 0.1 mm) is refused
// against a budget of 10,000 before any dexel is made, and built within one
// of 300,000.
TEST(Cutting, AModelBeyondItsDexelBudgetIsRefusedBeforeItIsBuilt) {
  const Plate plate;
  DexelOptions o;
  o.spacing_mm = 0.1;
  o.max_dexels = 10'000;
  try {
    (void)DexelModel::build(plate.mesh, plate.ids, plate.stock, o);
    FAIL() << "built beyond the budget";
  } catch (const std::length_error& e) {
    EXPECT_NE(std::string::npos, std::string(e.what()).find("dexels (about")) << e.what();
    EXPECT_NE(std::string::npos, std::string(e.what()).find("more than max-dexels 10000"))
        << e.what();
  }
  o.max_dexels = 300'000;
  EXPECT_GT(DexelModel::build(plate.mesh, plate.ids, plate.stock, o).size(), 80'000u);
  o.max_dexels = kMaxDexels + 1;
  EXPECT_THROW((void)DexelModel::build(plate.mesh, plate.ids, plate.stock, o),
               std::invalid_argument);
}

TEST(Cutting, FlatEndMillStraightCutLeavesTheProgrammedDepth) {
  // The path is off the dexel rows (y = 10.03): a tool edge exactly on a row
  // of dexels is a tangency that misses them, half a row of area per side.
  DexelModel m = Plate{}.build();
  const CutterShape flat{3, 0, 10};
  const Engagement e = m.cut(flat, at(-5, 10.03, 0.8), at(45, 10.03, 0.8));
  EXPECT_FALSE(e.invalid_input);
  int inside = 0, outside = 0;
  for (std::size_t i = 0; i < m.size(); ++i) {
    const double dy = std::abs(m.position(i).y() - 10.03);
    if (dy < 2.95) {
      ASSERT_NEAR(0.8, m.height_mm(i), kTol) << m.position(i).transpose();
      ++inside;
    } else if (dy > 3.05) {
      ASSERT_EQ(2.0, m.height_mm(i)) << m.position(i).transpose();
      ++outside;
    }
  }
  EXPECT_GT(inside, 20000);
  EXPECT_GT(outside, 20000);
  // 6 mm wide, 1.2 mm deep, 40 mm long.
  EXPECT_NEAR(6 * 1.2 * 40, e.removed_mm3, 0.01 * 6 * 1.2 * 40);
  EXPECT_NEAR(e.removed_mm3, m.removed_total_mm3(), 1e-9);
  EXPECT_NEAR(1.0, e.normal.z(), 1e-12);
  EXPECT_NEAR(10.03, e.contact_mm.y(), 0.01);
  EXPECT_NEAR(1.4, e.contact_mm.z(), 1e-9);  // middle of the removed layer
  EXPECT_NEAR(0.0, e.axial_min_mm, 1e-12);
  EXPECT_GT(e.substeps, 100u);
}

TEST(Cutting, PeripheralCutPutsTheWallAtPathPlusRadius) {
  // Wall x = 0 facing −x, y ∈ [0, 20], z ∈ [0, 10]; stock 2 mm beyond it.
  const TriangleMesh wall =
      grid({0, 0, 0}, Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitY(), 20, 40, 0.5);
  const std::vector<int> ids(wall.triangles.size(), 1);
  const std::vector<StockBox> stock{{{-2, 0, 0}, {10, 20, 10}}};
  DexelModel m = DexelModel::build(wall, ids, stock, {});
  ASSERT_NEAR(-1.0, m.normal(0).x(), 1e-12);
  const double r = 2.5, path_x = -0.5 - r;  // leaves the wall at x = −0.5
  m.cut({r, 0, 20}, at(path_x, -5, -1), at(path_x, 25, -1));
  for (std::size_t i = 0; i < m.size(); ++i)
    ASSERT_NEAR(0.5, m.height_mm(i), kTol) << m.position(i).transpose();
}

TEST(Cutting, BallEndRasterLeavesTheTextbookScallop) {
  // Passes along x every s = 1 mm; cusps at y = k + 0.5 (dexels there).
  DexelModel m = Plate{}.build(0.1);
  const double r = 3, s = 1.0, z = 0.3;
  for (int k = 0; k <= 20; ++k)
    m.cut({r, r, 12}, at(2, k * s, z), at(38, k * s, z));
  const double scallop = r - std::sqrt(r * r - (s / 2) * (s / 2));  // 41.9 µm
  double lo = 1e9, hi = -1e9;
  for (std::size_t i = 0; i < m.size(); ++i) {
    const Eigen::Vector3d& p = m.position(i);
    if (p.x() < 5 || p.x() > 35 || p.y() < 5 || p.y() > 15) continue;
    lo = std::min(lo, m.height_mm(i));
    hi = std::max(hi, m.height_mm(i));
    const double dy = std::abs(p.y() - std::round(p.y()));  // distance to the nearest pass
    const double expected = z + r - std::sqrt(r * r - dy * dy);
    ASSERT_NEAR(expected, m.height_mm(i), kTol) << p.transpose();
  }
  std::printf("ball raster: scallop %.3f um (textbook %.3f um)\n", (hi - lo) * 1e3, scallop * 1e3);
  EXPECT_NEAR(z, lo, 1e-6);
  EXPECT_NEAR(z + scallop, hi, kTol);
  EXPECT_NEAR(z + scallop, hi, 1e-3);  // dexels sit on the cusps: tighter than promised
}

TEST(Cutting, BullNoseProfileAcrossTheCut) {
  DexelModel m = Plate{}.build(0.1);
  const double r = 3, rc = 1, z = 0.5;
  m.cut({r, rc, 10}, at(2, 10, z), at(38, 10, z));
  for (std::size_t i = 0; i < m.size(); ++i) {
    const Eigen::Vector3d& p = m.position(i);
    if (p.x() < 5 || p.x() > 35) continue;
    const double u = std::abs(p.y() - 10);
    double expected = 2.0;
    if (u <= r - rc)
      expected = z;
    else if (std::abs(u - r) < 0.01)
      continue;  // on the rim: either side is right
    else if (u < r)
      expected = std::min(2.0, z + rc - std::sqrt(rc * rc - (u - (r - rc)) * (u - (r - rc))));
    ASSERT_NEAR(expected, m.height_mm(i), kTol) << p.transpose();
  }
}

TEST(Cutting, BullNoseLyingInsideTheMaterialCutsFromItsLowestPoint) {
  // Axis along +x, tip at z = 1 in stock up to z = 3: the vertical dexel lines
  // at 0 < x − tip_x < rc pass through the rounded bottom without reaching
  // either end of the material (the overhang case); the z-map rule removes
  // down to the tool's lowest point on the line: z = tip_z − √(r(w)² − dy²),
  // r(w) = ρ + √(rc² − (rc − w)²).
  Plate plate;
  plate.stock = {{{0, 0, -5}, {40, 20, 3}}};
  DexelModel m = plate.build(0.1);
  const double r = 1.5, rc = 1, tx = 20, ty = 10, tz = 1.0;
  const CutterPose pose = at(tx, ty, tz, Eigen::Vector3d::UnitX());
  m.cut({r, rc, 10}, pose, pose);
  int checked = 0;
  for (std::size_t i = 0; i < m.size(); ++i) {
    const Eigen::Vector3d& p = m.position(i);
    const double w = p.x() - tx, dy = p.y() - ty;
    if (w < 0.05 || w > 0.95) continue;
    const double rw = (r - rc) + std::sqrt(rc * rc - (rc - w) * (rc - w));
    if (std::abs(dy) > rw - 0.05) continue;
    ASSERT_NEAR(tz - std::sqrt(rw * rw - dy * dy), m.height_mm(i), kTol) << p.transpose();
    ++checked;
  }
  EXPECT_GT(checked, 200);
}

TEST(Cutting, TiltedFlatEndMillCutsAnInclinedFloor) {
  // 5-axis: axis tilted 10° towards +x, moving along y. The bottom disk is
  // the plane z = tip_z − (x − tip_x)·tan θ within ±R cos θ of the tip.
  DexelModel m = Plate{}.build(0.1);
  const double th = 10 * std::numbers::pi / 180, r = 3, tx = 20, tz = 1.0;
  const Eigen::Vector3d axis(std::sin(th), 0, std::cos(th));
  m.cut({r, 0, 15}, at(tx, -5, tz, axis), at(tx, 25, tz, axis));
  int checked = 0;
  for (std::size_t i = 0; i < m.size(); ++i) {
    const Eigen::Vector3d& p = m.position(i);
    const double u = p.x() - tx;
    if (std::abs(u) > r * std::cos(th) - 0.05 || p.y() < 5 || p.y() > 15) continue;
    const double expected = std::min(2.0, tz - u * std::tan(th));
    ASSERT_NEAR(expected, m.height_mm(i), kTol) << p.transpose();
    ++checked;
  }
  EXPECT_GT(checked, 5000);
}

TEST(Cutting, RotaryMoveAboutTheTipCutsAVGroove) {
  // Axis swings from −θ to +θ about y with the tip fixed: the union of the
  // tilted bottoms is z = tip_z − |x − tip_x|·tan θ (sub-steps make it so).
  DexelModel m = Plate{}.build(0.1);
  const double th = 8 * std::numbers::pi / 180, r = 3, tx = 20, ty = 10, tz = 1.0;
  const Engagement e = m.cut({r, 0, 15}, at(tx, ty, tz, {-std::sin(th), 0, std::cos(th)}),
                             at(tx, ty, tz, {std::sin(th), 0, std::cos(th)}));
  EXPECT_GT(e.substeps, 50u);
  int checked = 0;
  for (std::size_t i = 0; i < m.size(); ++i) {
    const Eigen::Vector3d& p = m.position(i);
    const double u = p.x() - tx;
    if (std::abs(u) > 2.0 || std::abs(p.y() - ty) > 1.0) continue;
    ASSERT_NEAR(tz - std::abs(u) * std::tan(th), m.height_mm(i), kTol) << p.transpose();
    ++checked;
  }
  EXPECT_GT(checked, 500);
}

TEST(Cutting, CombinedTranslationAndRotationFollowsTheSweptBall) {
  // Ball R = 3: the tip moves 2 mm along x while the axis turns from −20° to
  // +20° about y. Reference: the lower envelope of 4001 ball positions.
  DexelModel m = Plate{}.build(0.1);
  const double r = 3, th = 20 * std::numbers::pi / 180, tx = 20, ty = 10, tz = 0.5;
  auto axis = [&](double psi) { return Eigen::Vector3d(std::sin(psi), 0, std::cos(psi)); };
  const Engagement e =
      m.cut({r, r, 12}, at(tx - 1, ty, tz, axis(-th)), at(tx + 1, ty, tz, axis(th)));
  EXPECT_GT(e.substeps, 20u);
  int checked = 0;
  double worst = 0;
  for (std::size_t i = 0; i < m.size(); ++i) {
    const Eigen::Vector3d& p = m.position(i);
    if (std::abs(p.x() - tx) > 1.5 || std::abs(p.y() - ty) > 1.5) continue;
    double ref = 2.0;
    for (int k = 0; k <= 4000; ++k) {
      const double s = k / 4000.0;
      const Eigen::Vector3d c =
          Eigen::Vector3d(tx - 1 + 2 * s, ty, tz) + r * axis(-th + 2 * th * s);
      const double q =
          r * r - (p.x() - c.x()) * (p.x() - c.x()) - (p.y() - c.y()) * (p.y() - c.y());
      if (q >= 0) ref = std::min(ref, c.z() - std::sqrt(q));
    }
    worst = std::max(worst, std::abs(ref - m.height_mm(i)));
    ASSERT_NEAR(ref, m.height_mm(i), kTol) << p.transpose();
    ++checked;
  }
  EXPECT_GT(checked, 1000);
  std::printf("combined move: %d dexels, worst deviation from the reference %.2f um\n", checked,
              worst * 1e3);
}

TEST(Cutting, NothingIsCutWhereTheToolDoesNotReach) {
  DexelModel m = Plate{}.build(0.2);
  const CutterShape ball{3, 3, 12};
  Engagement e = m.cut(ball, at(-5, 10, 2.001), at(45, 10, 2.001));  // 1 µm above the stock
  EXPECT_EQ(0.0, e.removed_mm3);
  EXPECT_EQ(0u, e.dexels_touched);
  e = m.cut(ball, at(-10, 30, 0), at(50, 30, 0));  // beside the plate, 10 mm off
  EXPECT_EQ(0.0, e.removed_mm3);
  EXPECT_EQ(0.0, m.removed_total_mm3());
  EXPECT_EQ(Eigen::Vector3d::Zero(), e.normal);
}

TEST(Cutting, SlotVolumeIsWidthTimesDepthTimesLength) {
  DexelModel m = Plate{}.build(0.1);
  const double r = 2, depth = 1.5, length = 25;
  // Inside the plate: the slot has round ends (π r² · depth more).
  const Engagement e =
      m.cut({r, 0, 10}, at(8.02, 10.03, 2 - depth), at(8.02 + length, 10.03, 2 - depth));
  const double expected = depth * (2 * r * length + std::numbers::pi * r * r);
  EXPECT_NEAR(expected, e.removed_mm3, 0.01 * expected);
  EXPECT_NEAR(expected, m.removed_total_mm3(), 0.01 * expected);
  // The second pass in the same slot removes nothing.
  EXPECT_EQ(0.0, m.cut({r, 0, 10}, at(8.02, 10.03, 2 - depth), at(8.02 + length, 10.03, 2 - depth))
                     .removed_mm3);
}

TEST(Cutting, GougesAreClampedAtMaxDepth) {
  DexelModel m = Plate{}.build(0.2);
  m.cut({2, 0, 10}, at(10, 10, -3), at(12, 10, -3));  // 3 mm below nominal
  double lowest = 0;
  for (std::size_t i = 0; i < m.size(); ++i)
    lowest = std::min(lowest, m.height_mm(i));
  EXPECT_EQ(-0.5, lowest);
}

TEST(Cutting, SharpEdgeDexelsIgnoreAToolFlushWithTheNeighbouringFace) {
  // A block's top z = 0 and its side x = 0 (facing −x): face milling the top
  // exactly at z = 0 must not gouge the side's top-edge dexels.
  TriangleMesh top =
      grid({0, 0, 0}, Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), 10, 10, 0.5);
  const TriangleMesh side =
      grid({0, 0, -5}, Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitY(), 10, 10, 0.5);
  const auto base = std::uint32_t(top.vertices_mm.size());
  top.vertices_mm.insert(top.vertices_mm.end(), side.vertices_mm.begin(), side.vertices_mm.end());
  std::vector<int> ids(top.triangles.size(), 1);
  for (auto t : side.triangles) {
    top.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
    ids.push_back(2);
  }
  const std::vector<StockBox> stock{{{-0.3, 0, -5}, {5, 5, 0.3}}};
  DexelModel m = DexelModel::build(top, ids, stock, {});
  m.cut({4, 0, 10}, at(-5, 2.5, 0), at(10, 2.5, 0));
  for (std::size_t i = 0; i < m.size(); ++i) {
    const Eigen::Vector3d& p = m.position(i);
    if (m.surface(i) == 2 && std::abs(p.y() - 2.5) < 3) {
      ASSERT_GE(m.height_mm(i), 0.3 - 1e-9) << p.transpose();  // the side's allowance remains
    }
    if (m.surface(i) == 1 && std::abs(p.y() - 2.5) < 3.9) {
      ASSERT_NEAR(0.0, m.height_mm(i), 1e-12) << p.transpose();
    }
  }
}

TEST(Cutting, InvalidToolCutsNothing) {
  DexelModel m = Plate{}.build(0.5);
  EXPECT_TRUE(m.cut({0, 0, 10}, at(0, 0, 0), at(1, 0, 0)).invalid_input);
  EXPECT_TRUE(m.cut({2, 3, 10}, at(0, 0, 0), at(1, 0, 0)).invalid_input);
  EXPECT_TRUE(m.cut({2, 0, 10}, at(NAN, 0, 0), at(1, 0, 0)).invalid_input);
  EXPECT_TRUE(m.cut({2, 0, 10}, at(0, 0, 0, Eigen::Vector3d::Zero()), at(1, 0, 0)).invalid_input);
  EXPECT_EQ(0.0, m.removed_total_mm3());
}

TEST(Cutting, ForceModelFollowsTheSpecificCuttingForce) {
  Engagement e;
  e.removed_mm3 = 0.05;  // in 1 ms: 50 mm³/s
  e.normal = Eigen::Vector3d(0, 0, 1);
  const ForceModel fm{1800, 0.4};
  const CuttingLoad l = cutting_load(e, 1e-3, 3, 10000, fm);
  EXPECT_DOUBLE_EQ(50.0, l.mrr_mm3_per_s);
  EXPECT_NEAR(1800 * 50 * 1e-3, l.power_w, 1e-9);       // 90 W
  const double vc = std::numbers::pi * 6 * 10000 / 60;  // mm/s
  EXPECT_NEAR(90e3 / vc, l.tangential_force_n, 1e-9);
  EXPECT_NEAR(0.4 * 90e3 / vc, l.force_n.z(), 1e-9);
  EXPECT_EQ(0.0, cutting_load(e, 1e-3, 3, 0, fm).force_n.norm());  // no spindle
  EXPECT_EQ(0.0, cutting_load(e, 0, 3, 10000, fm).power_w);
}

TEST(Cutting, SameCutsGiveIdenticalMeshBytes) {
  const auto dir = truecut::test::scratch_dir();
  std::string stl[2], ply[2];
  for (int run = 0; run < 2; ++run) {
    DexelModel m = Plate{}.build(0.25);
    const Eigen::Vector3d axis = Eigen::Vector3d(0.2, -0.1, 1).normalized();
    m.cut({3, 1, 12}, at(-5, 3, 0.4, axis), at(45, 17, 0.9));
    m.cut({3, 3, 12}, at(40, 0, 0.2), at(0, 20, 0.7, axis));
    const auto out = dir / std::to_string(run);
    std::filesystem::create_directories(out);
    m.write_machined(out);
    stl[run] = truecut::test::read_file(out / "machined.stl");
    ply[run] = truecut::test::read_file(out / "machined.ply");
    EXPECT_FALSE(std::filesystem::exists(out / "machined.stl.tmp"));
  }
  EXPECT_GT(stl[0].size(), 84u + 50 * 40000);
  EXPECT_EQ(stl[0], stl[1]);
  EXPECT_EQ(ply[0], ply[1]);
}

TEST(Cutting, MachinedMeshMovesVerticesAlongTheirNormals) {
  DexelModel m = Plate{}.build(1.0);
  m.cut({3, 0, 10}, at(-5, 10, 0.8), at(45, 10, 0.8));
  const TriangleMesh out = m.machined_mesh();
  ASSERT_EQ(m.size(), out.vertices_mm.size());
  for (std::size_t i = 0; i < m.size(); ++i)
    ASSERT_EQ(m.position(i) + m.height_mm(i) * m.normal(i), out.vertices_mm[i]);
  EXPECT_EQ(2u * 80 * 40, out.triangles.size());  // cells of 0.5 mm, spacing 0.5: no subdivision
}

// The stock of a part can be hundreds of boxes (benchmark004: 384), found
// through a grid over them. Columns of stacked boxes over the plate, some
// with a gap: each dexel's height is where its column's material first
// ends above it, as the test walks the column's intervals itself.
TEST(Cutting, InitialHeightThroughHundredsOfStockBoxes) {
  Plate plate;
  std::vector<StockBox> stock;
  std::map<std::pair<int, int>, std::vector<std::pair<double, double>>> columns;
  std::uint64_t state = 12345;
  auto uniform = [&state] {  // splitmix64
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return double((z ^ (z >> 31)) >> 11) / double(1ull << 53);
  };
  for (int cx = 0; cx < 20; ++cx)
    for (int cy = 0; cy < 10; ++cy) {
      double z = -5;
      const int pieces = 1 + static_cast<int>(uniform() * 3);
      for (int k = 0; k < pieces; ++k) {
        const double top = z + 0.5 + 2.5 * uniform();
        stock.push_back({{2.0 * cx, 2.0 * cy, z}, {2.0 * cx + 2, 2.0 * cy + 2, top}});
        columns[{cx, cy}].push_back({z, top});
        z = top + (uniform() < 0.2 ? 0.3 : 0.0);  // a gap now and then
      }
    }
  ASSERT_GT(stock.size(), 300u);
  DexelOptions o;
  o.spacing_mm = 0.3;
  o.max_stock_mm = 50;
  const DexelModel m = DexelModel::build(plate.mesh, plate.ids, stock, o);
  std::size_t checked = 0;
  for (std::size_t i = 0; i < m.size(); ++i) {
    const Eigen::Vector3d p = m.position(i);
    const double fx = p.x() / 2 - std::floor(p.x() / 2), fy = p.y() / 2 - std::floor(p.y() / 2);
    if (fx < 1e-6 || fx > 1 - 1e-6 || fy < 1e-6 || fy > 1 - 1e-6) continue;  // on a column's side
    const auto& column = columns.at({static_cast<int>(p.x() / 2), static_cast<int>(p.y() / 2)});
    double reach = 0;  // from z = 0 up through contiguous intervals
    for (const auto& [lo, hi] : column)
      if (lo <= reach + 1e-9 && hi > reach) reach = hi;
    ASSERT_NEAR(m.initial_height_mm(i), std::max(reach, 0.0), 1e-9) << p.transpose();
    ++checked;
  }
  EXPECT_GT(checked, 5000u);
}
