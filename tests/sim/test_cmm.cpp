// Virtual CMM: deviations of a known offset surface, sign convention,
// invalid points, statistics, determinism, point files and part.json labels.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "test_paths.hpp"
#include "test_scanner_meshes.hpp"
#include "truecut/sim/benchmark_parts.hpp"
#include "truecut/sim/measure/cmm.hpp"
#include "truecut/sim/measure/part_surfaces.hpp"

using namespace truecut::sim::measure;
using truecut::offline::TriangleMesh;
using truecut::test::box_mesh;

namespace {

const Eigen::Vector3d kLo(-10, -8, 0), kHi(10, 8, 12);

struct Nominal {
  TriangleMesh mesh;
  std::vector<std::int32_t> ids;
};

Nominal nominal_box() {
  Nominal n;
  n.mesh = box_mesh(kLo, kHi, &n.ids);
  return n;
}

TriangleMesh translated(const TriangleMesh& m, const Eigen::Vector3d& t) {
  TriangleMesh out = m;
  for (auto& v : out.vertices_mm)
    v += t;
  return out;
}

const SurfaceDeviationStats& of(const std::vector<SurfaceDeviationStats>& s, int surface) {
  for (const auto& e : s)
    if (e.surface == surface) return e;
  throw std::runtime_error("no surface " + std::to_string(surface));
}

}  // namespace

TEST(Cmm, ShiftedMeshGivesTheShiftAlongEachNormal) {
  const Nominal nom = nominal_box();
  // Machined part shifted by 0.05 mm along +X: +X face 0.05 mm oversize,
  // −X face 0.05 mm undersize, the others on size.
  const TriangleMesh machined = translated(nom.mesh, {0.05, 0, 0});
  const std::vector<CmmPoint> points = cmm_points_on_surfaces(nom.mesh, nom.ids, 1.0);
  CmmOptions o;
  o.sigma_mm = 0.002;
  const auto m = probe(machined, points, o);
  ASSERT_EQ(points.size(), m.size());
  const auto stats = surface_statistics(m);
  const double expected[6] = {-0.05, 0.05, 0, 0, 0, 0};
  for (int f = 0; f < 6; ++f) {
    const SurfaceDeviationStats& s = of(stats, f);
    ASSERT_EQ(s.points, s.valid) << f;
    ASSERT_GT(s.valid, 100u) << f;
    // Mean within 3σ/√n of the truth; std dev of the 2 µm noise.
    EXPECT_NEAR(s.mean_um, 1000 * expected[f], 3 * 2.0 / std::sqrt(static_cast<double>(s.valid)))
        << f;
    EXPECT_NEAR(s.std_um, 2.0, 5 * 2.0 / std::sqrt(2.0 * static_cast<double>(s.valid - 1))) << f;
  }
  EXPECT_NEAR(of(stats, 1).rms_um, 50, 0.5);
  EXPECT_GT(of(stats, 1).max_abs_um, of(stats, 1).p95_abs_um);
  EXPECT_GT(of(stats, 1).p95_abs_um, 50);
  // Measured point = nominal + deviation · normal, on the machined +X face.
  for (const auto& e : m) {
    if (e.nominal.surface == 1) {
      ASSERT_NEAR(e.measured_mm.x(), 10.05, 0.012);
    }
  }
}

TEST(Cmm, WithoutNoiseTheOffsetIsExact) {
  const Nominal nom = nominal_box();
  const TriangleMesh grown = box_mesh(kLo.array() - 0.05, kHi.array() + 0.05);
  const TriangleMesh shrunk = box_mesh(kLo.array() + 0.05, kHi.array() - 0.05);
  CmmOptions o;
  o.sigma_mm = 0;
  const auto points = cmm_points_on_surfaces(nom.mesh, nom.ids, 2.0);
  for (const auto& e : probe(grown, points, o))
    ASSERT_NEAR(e.deviation_mm, 0.05, 1e-9);
  for (const auto& e : probe(shrunk, points, o))
    ASSERT_NEAR(e.deviation_mm, -0.05, 1e-9);
}

TEST(Cmm, PointsWithoutASurfaceAreFlaggedNotDropped) {
  const Nominal nom = nominal_box();
  std::vector<CmmPoint> points = {
      {{0, 0, 12.3}, {0, 0, 1}, 5},   // 0.3 mm above the top: found
      {{0, 0, 14.0}, {0, 0, 1}, 5},   // 2 mm above the top: beyond the 1 mm search
      {{0, 0, 12.0}, {0, 0, -1}, 5},  // normal pointing into the part: wrong side
      {{0, 0, 6}, {1, 0, 0}, 1},      // inside, nearest wall 10 mm away
  };
  const auto m = probe(nom.mesh, points, CmmOptions{});
  ASSERT_EQ(4u, m.size());
  EXPECT_TRUE(m[0].valid);
  EXPECT_NEAR(-0.3, m[0].deviation_mm, 0.012);
  for (int i : {1, 2, 3}) {
    EXPECT_FALSE(m[static_cast<std::size_t>(i)].valid) << i;
    EXPECT_TRUE(std::isnan(m[static_cast<std::size_t>(i)].deviation_mm)) << i;
  }
  const auto s = of(surface_statistics(m), 5);
  EXPECT_EQ(3u, s.points);
  EXPECT_EQ(1u, s.valid);
}

TEST(Cmm, StatisticsByHand) {
  std::vector<CmmMeasurement> m;
  for (double d_um : {-4.0, 1.0, 2.0, 3.0, 10.0}) {
    CmmMeasurement e;
    e.nominal.surface = 3;
    e.valid = true;
    e.deviation_mm = d_um / 1000;
    m.push_back(e);
  }
  m.push_back({});  // surface −1, invalid
  const auto s = of(surface_statistics(m), 3);
  EXPECT_EQ(5u, s.valid);
  EXPECT_NEAR(2.4, s.mean_um, 1e-9);
  EXPECT_NEAR(std::sqrt(130.0 / 5), s.rms_um, 1e-9);
  EXPECT_NEAR(std::sqrt((130.0 - 5 * 2.4 * 2.4) / 4), s.std_um, 1e-9);
  EXPECT_NEAR(10, s.max_abs_um, 1e-9);
  // |dev| sorted 1 2 3 4 10; rank 0.95·4 = 3.8 → 4 + 0.8·6.
  EXPECT_NEAR(8.8, s.p95_abs_um, 1e-9);
  const auto all = overall_statistics(m);
  EXPECT_EQ(6u, all.points);
  EXPECT_EQ(5u, all.valid);
}

TEST(Cmm, DeterministicPerSeed) {
  const Nominal nom = nominal_box();
  const auto points = cmm_points_on_surfaces(nom.mesh, nom.ids, 2.0);
  CmmOptions o;
  const auto a = probe(nom.mesh, points, o), b = probe(nom.mesh, points, o);
  o.seed = 9;
  const auto c = probe(nom.mesh, points, o);
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].deviation_mm, b[i].deviation_mm);
    ASSERT_NE(a[i].deviation_mm, c[i].deviation_mm);
  }
}

TEST(Cmm, CsvWritesAndReadsBack) {
  const Nominal nom = nominal_box();
  const auto points = cmm_points_on_surfaces(nom.mesh, nom.ids, 4.0);
  auto m = probe(nom.mesh, points, CmmOptions{});
  m.push_back({{{0, 0, 30}, {0, 0, 1}, 5}, false, std::nan(""), {}});
  const auto file = truecut::test::scratch_dir() / "cmm.csv";
  write_cmm_csv(file, m);
  const std::string text = truecut::test::read_file(file);
  EXPECT_EQ(0u, text.find("x,y,z,nx,ny,nz,surface,deviation_mm,valid\n"));
  EXPECT_NE(std::string::npos, text.find("0,0,30,0,0,1,5,nan,0\n"));
  EXPECT_FALSE(std::filesystem::exists(file.string() + ".tmp"));
  const auto back = read_cmm_points(file);
  ASSERT_EQ(m.size(), back.size());
  for (std::size_t i = 0; i < m.size(); ++i) {
    ASSERT_EQ(m[i].nominal.position_mm, back[i].position_mm);
    ASSERT_EQ(m[i].nominal.surface, back[i].surface);
  }
}

TEST(Cmm, PointFileErrorsNameFileAndLine) {
  const auto dir = truecut::test::scratch_dir();
  auto expect_error = [&](const std::string& text, const std::string& fragment) {
    const auto file = dir / "p.txt";
    std::ofstream(file) << text;
    try {
      read_cmm_points(file);
      ADD_FAILURE() << "no error for: " << text;
    } catch (const CmmInputError& e) {
      EXPECT_NE(std::string::npos, std::string(e.what()).find(fragment)) << e.what();
    }
  };
  expect_error("0 0 0 0 0 1\n1 2 3 0 0\n", "p.txt:2: expected 6 or 7 values");
  expect_error("# points\n0 0 0 0 0 1 4\n0 0 x 0 0 1\n", "p.txt:3: 'x' is not a finite number");
  expect_error("0 0 0 0 0 0\n", "p.txt:1: zero normal");
  expect_error("0 0 0 0 0 1 2.5\n", "p.txt:1: surface id");
  expect_error("x y z nx ny\n", "p.txt:1: header lacks the column 'nz'");
  expect_error("\n# nothing\n", "p.txt: no points");
  // Accepted: commas, semicolons, a header in another order, a surface column.
  const auto file = dir / "ok.csv";
  std::ofstream(file) << "surface;nz;ny;nx;z;y;x\n7;2;0;0;3;2;1\n";
  const auto p = read_cmm_points(file);
  ASSERT_EQ(1u, p.size());
  EXPECT_EQ(Eigen::Vector3d(1, 2, 3), p[0].position_mm);
  EXPECT_EQ(Eigen::Vector3d(0, 0, 1), p[0].normal);
  EXPECT_EQ(7, p[0].surface);
}

TEST(Cmm, PartJsonLabelsOfABenchmarkPart) {
  const auto part = truecut::sim::make_part(truecut::sim::PartId::kImplant, {2.0, 0.8, 1.0, 2.0});
  const auto dir = truecut::test::scratch_dir();
  truecut::sim::write_part(part, dir);
  const PartSurfaces labels = read_part_surfaces(dir / "part.json");
  EXPECT_EQ(part.triangle_surface, labels.triangle_surface_ids);
  EXPECT_EQ((std::vector<std::int32_t>{1, 2, 3, 4, 5}), labels.compensated_ids());
  // The nominal part measured against itself: every point valid, noise only.
  const auto points =
      cmm_points_on_surfaces(part.mesh, labels.triangle_surface_ids, 0.5, labels.compensated_ids());
  const auto m = probe(part.mesh, points, CmmOptions{});
  const auto all = overall_statistics(m);
  EXPECT_EQ(all.points, all.valid);
  EXPECT_NEAR(0, all.mean_um, 5 * 2 / std::sqrt(static_cast<double>(all.valid)));

  std::ofstream(dir / "bad.json")
      << R"({"surfaces": [{"id": 1}], "triangle_surface_ids": [1, "x"]})";
  try {
    read_part_surfaces(dir / "bad.json");
    ADD_FAILURE();
  } catch (const PartFileError& e) {
    EXPECT_NE(std::string::npos,
              std::string(e.what()).find("bad.json: key 'triangle_surface_ids[1]'"))
        << e.what();
  }
}
