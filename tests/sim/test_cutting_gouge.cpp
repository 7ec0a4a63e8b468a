// Exploratory: the implant's peripheral pass translated along X.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>

#include "test_paths.hpp"
#include "truecut/sim/benchmark_parts.hpp"
#include "truecut/sim/cutting/dexel_model.hpp"
#include "truecut/sim/cutting/part_file.hpp"

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
    if (have) m.cut(shape, last, next, false);
    else m.cut(shape, next, next, true);
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
    while (a1 > a0) a1 -= 2 * M_PI;
    const int n = std::max(1, int(std::ceil(r * (a0 - a1) / step)));
    for (int k = 1; k <= n; ++k) {
      const double t = a0 + (a1 - a0) * double(k) / n;
      to({c.x() + r * std::cos(t), c.y() + r * std::sin(t), a.z()});
    }
  }
};

void implant_program(DexelModel& m, const Eigen::Vector3d& offset) {
  PathCutter top{m, {2.0, 0, 8.0}, offset, {}, false};
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

}  // namespace

TEST(CuttingGouge, Explore) {
  const auto part = make_part(PartId::kImplant, {0.25, 0.8, 1.0, 2.0});
  const auto dir = truecut::test::scratch_dir();
  write_part(part, dir / "implant");
  for (double cx : {0.0, 0.03}) {
    DexelModel m = load_dexel_model(dir / "implant" / "nominal.stl", dir / "implant" / "part.json", {});
    implant_program(m, {cx, 0, 0});
    std::map<std::pair<int, long>, std::pair<double, int>> col;  // (surface, y µm) → sum, n
    for (std::size_t i = 0; i < m.size(); ++i) {
      const int s = m.surface(i);
      if (s != 1 && s != 2) continue;
      const auto& q = m.position(i);
      if (q.z() < 0.3 || q.z() > 16.7) continue;
      auto& e = col[{s, std::lround(q.y() * 1000)}];
      e.first += m.height_mm(i);
      ++e.second;
    }
    std::printf("cx = %.3f\n", cx);
    for (const auto& [k, v] : col)
      std::printf("  surface %d y %+.3f: mean h %+.4f (%d)\n", k.first, k.second / 1000.0,
                  v.first / v.second, v.second);
  }
}
