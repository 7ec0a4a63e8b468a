// The implant's program (face milling of the top, peripheral milling of the
// shaft) with its path translated: a face the tool is driven into must end
// below nominal by the translation (h < 0), a face it moves away from above,
// on every dexel and on the machined mesh as the CMM probes it — also next
// to the sharp edges, where the neighbouring face's edge dexels are cut
// through (convex) or keep the oversize material (concave).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>

#include "test_paths.hpp"
#include "truecut/sim/benchmark_parts.hpp"
#include "truecut/sim/cutting/dexel_model.hpp"
#include "truecut/sim/cutting/part_file.hpp"
#include "truecut/sim/measure/cmm.hpp"

using namespace truecut::sim;
using namespace truecut::sim::cutting;

namespace {

// Servo-cycle steps along a polyline/arc path.
struct PathCutter {
  DexelModel& m;
  CutterShape shape;
  Eigen::Vector3d offset;
  CutterPose last;
  bool have = false;
  void to(const Eigen::Vector3d& p) {
    CutterPose next{p + offset, Eigen::Vector3d::UnitZ()};
    if (have)
      m.cut(shape, last, next, false);
    else
      m.cut(shape, next, next, true);
    last = next;
    have = true;
  }
  void line(const Eigen::Vector3d& b, double step = 0.0083) {
    const Eigen::Vector3d a = last.tip_mm - offset;
    const int n = std::max(1, int(std::ceil((b - a).norm() / step)));
    for (int k = 1; k <= n; ++k)
      to(a + (b - a) * (double(k) / n));
  }
  // Clockwise arc about centre c to b.
  void arc_cw(const Eigen::Vector3d& b, const Eigen::Vector3d& c, double step = 0.0083) {
    const Eigen::Vector3d a = last.tip_mm - offset;
    const double r = (a - c).head<2>().norm();
    const double a0 = std::atan2(a.y() - c.y(), a.x() - c.x());
    double a1 = std::atan2(b.y() - c.y(), b.x() - c.x());
    while (a1 > a0)
      a1 -= 2 * std::numbers::pi;
    const int n = std::max(1, int(std::ceil(r * (a0 - a1) / step)));
    for (int k = 1; k <= n; ++k) {
      const double t = a0 + (a1 - a0) * double(k) / n;
      to({c.x() + r * std::cos(t), c.y() + r * std::sin(t), a.z()});
    }
  }
};

void implant_program(DexelModel& m, const Eigen::Vector3d& offset, double top_dz) {
  PathCutter top{m, {2.0, 0, 8.0}, offset + Eigen::Vector3d(0, 0, top_dz), {}, false};
  const double xo = 0.8 + 2.0 + 0.5;
  for (double y : {-0.8, 0.0, 0.8}) {
    top.have = false;
    top.to({-xo, y, 17});
    top.line({xo, y, 17});
  }
  PathCutter p{m, {1.0, 0, 20.0}, offset, {}, false};
  const double a = 0.8, r = 1.0, c = a + r, lead = 2.0 + r + 0.3;
  std::vector<double> zs;
  for (int k = 1;; ++k) {
    const double z = 17 - 2.0 * k;
    if (z <= 1e-9) break;
    zs.push_back(z);
  }
  zs.push_back(0.0);
  for (double z : zs) {
    p.have = false;
    p.to({-a - lead, c, z + 1});
    p.line({-a - lead, c, z});
    p.line({a, c, z});
    p.arc_cw({c, a, z}, {a, a, z});
    p.line({c, -a, z});
    p.arc_cw({a, -c, z}, {a, -a, z});
    p.line({-a, -c, z});
    p.arc_cw({-c, -a, z}, {-a, -a, z});
    p.line({-c, a, z});
    p.arc_cw({-a, c, z}, {-a, a, z});
    p.line({a + lead, c, z});
  }
}

constexpr int kXPos = 1, kXNeg = 2, kYPos = 3, kYNeg = 4, kTop = 5;
constexpr double kTol = 5e-3;

// Machines the implant with the path translated by (cx, 0, 0) and the top
// face pass lowered by top_dz; checks every shaft-face dexel and the
// machined mesh probed on a grid of each face (edges included down to
// 0.1 mm).
void expect_translated_faces(double cx, double top_dz) {
  SCOPED_TRACE("cx " + std::to_string(cx) + ", top " + std::to_string(top_dz));
  const auto part = make_part(PartId::kImplant, {0.25, 0.8, 1.0, 2.0});
  const auto dir = truecut::test::scratch_dir();
  write_part(part, dir / "implant");
  DexelModel m =
      load_dexel_model(dir / "implant" / "nominal.stl", dir / "implant" / "part.json", {});
  implant_program(m, {cx, 0, 0}, top_dz);
  const std::map<int, double> want = {
      {kXPos, cx}, {kXNeg, -cx}, {kYPos, 0.0}, {kYNeg, 0.0}, {kTop, top_dz}};
  int checked = 0;
  for (std::size_t i = 0; i < m.size(); ++i) {
    const auto it = want.find(m.surface(i));
    if (it == want.end()) continue;
    const Eigen::Vector3d& p = m.position(i);
    // Away from the shaft's vertical edges and the top rim, which the
    // tool's corners and the neighbouring face's pass shape.
    const double side = std::max(std::abs(p.x()), std::abs(p.y()));
    const double along = std::min(std::abs(p.x()), std::abs(p.y()));
    if (it->first != kTop && (along > 0.7 || p.z() > 16.9 || p.z() < 0.1)) continue;
    if (it->first == kTop && side > 0.7) continue;
    ASSERT_NEAR(it->second, m.height_mm(i), kTol)
        << "surface " << it->first << " at " << p.transpose();
    ++checked;
  }
  EXPECT_GT(checked, 25000);

  // The machined mesh, probed along the nominal normals (no noise).
  std::vector<measure::CmmPoint> pts;
  for (double z = 0.1; z < 16.95; z += 0.25)
    for (double u = -0.7; u <= 0.7001; u += 0.05) {
      pts.push_back({{0.8, u, z}, Eigen::Vector3d::UnitX(), kXPos});
      pts.push_back({{-0.8, u, z}, -Eigen::Vector3d::UnitX(), kXNeg});
      pts.push_back({{u, 0.8, z}, Eigen::Vector3d::UnitY(), kYPos});
      pts.push_back({{u, -0.8, z}, -Eigen::Vector3d::UnitY(), kYNeg});
    }
  for (double x = -0.7; x <= 0.7001; x += 0.1)
    for (double y = -0.7; y <= 0.7001; y += 0.1)
      pts.push_back({{x, y, 17}, Eigen::Vector3d::UnitZ(), kTop});
  measure::CmmOptions o;
  o.sigma_mm = 0;
  const auto got = measure::probe(m.machined_mesh(), pts, o);
  for (std::size_t i = 0; i < got.size(); ++i) {
    ASSERT_TRUE(got[i].valid) << pts[i].position_mm.transpose();
    ASSERT_NEAR(want.at(pts[i].surface), got[i].deviation_mm, kTol)
        << "surface " << pts[i].surface << " at " << pts[i].position_mm.transpose();
  }
}

}  // namespace

// +X: the tool 30 µm into the −X face (convex edges: the ±Y faces' edge
// dexels there are cut through) and 30 µm off the +X face (concave edge at
// the base: the base top's edge dexels keep the oversize material up to the
// stock cap); the top face pass 30 µm below nominal.
TEST(CuttingGouge, PathTranslatedIntoAFaceCutsItBelowNominal) {
  expect_translated_faces(0.03, -0.03);
}

// The mirror case: into the +X face, off the −X face; the top 30 µm high.
TEST(CuttingGouge, PathTranslatedOutOfAFaceLeavesItOversize) {
  expect_translated_faces(-0.03, 0.03);
}

// Deeper than the dexel spacing (0.057 mm): the neighbouring faces' edge
// rows are cut through (or kept) over two dexels.
TEST(CuttingGouge, GougeWiderThanTheDexelSpacing) {
  expect_translated_faces(0.08, 0.0);
}

TEST(CuttingGouge, NominalPathLeavesTheNominalSurface) {
  expect_translated_faces(0.0, 0.0);
}
