// The k-d tree under every spatial query of the field pipeline (scan
// points, placement probes, sharp-edge pieces), against brute force.
#include "spatial/kd_tree.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

namespace truecut::offline::spatial {
namespace {

std::vector<std::uint32_t> brute_within(const std::vector<Eigen::Vector3d>& p,
                                        const Eigen::Vector3d& q, double r) {
  std::vector<std::uint32_t> out;
  for (std::uint32_t i = 0; i < p.size(); ++i)
    if ((p[i] - q).squaredNorm() <= r * r) out.push_back(i);
  return out;
}

// Clustered, duplicated and lattice points (many on the same split planes),
// queried at random points and radii.
TEST(KdTree, WithinFindsWhatBruteForceFinds) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-10.0, 10.0), radius(0.0, 4.0);
  std::vector<Eigen::Vector3d> p;
  for (int i = 0; i < 3000; ++i)
    p.emplace_back(u(rng), u(rng), 0.01 * u(rng));  // a thin sheet
  for (int i = 0; i < 500; ++i)
    p.push_back(p[static_cast<std::size_t>(i) * 3]);  // duplicates
  for (int i = -5; i <= 5; ++i)
    for (int j = -5; j <= 5; ++j)
      for (int k = -2; k <= 2; ++k)
        p.emplace_back(i, j, k);  // a lattice: distances hit the radius exactly
  const KdTree tree(p);
  std::vector<std::uint32_t> found, again;
  for (int n = 0; n < 400; ++n) {
    const Eigen::Vector3d q = n % 4 == 0
                                  ? Eigen::Vector3d(std::round(u(rng)), std::round(u(rng)), 0.0)
                                  : Eigen::Vector3d(u(rng), u(rng), u(rng) * 0.1);
    const double r = n % 4 == 0 ? std::round(radius(rng)) : radius(rng);
    found.clear();
    tree.within(q, r, found);
    again.clear();
    tree.within(q, r, again);
    EXPECT_EQ(found, again) << "the order of the points is the tree's, the same every time";
    std::sort(found.begin(), found.end());
    ASSERT_EQ(found, brute_within(p, q, r))
        << "query " << n << " at " << q.transpose() << " r " << r;
  }
}

TEST(KdTree, PointsOnTheSphereAreWithinIt) {
  std::vector<Eigen::Vector3d> p;
  for (int a = 0; a < 3; ++a)
    for (double s : {-1.0, 1.0}) {
      Eigen::Vector3d x = Eigen::Vector3d::Zero();
      x[a] = 2.5 * s;
      p.push_back(Eigen::Vector3d(0.5, -0.25, 1.0) + x);
    }
  for (int i = 0; i < 64; ++i)  // enough points for inner nodes
    p.emplace_back(10.0 + i, 10.0, 10.0);
  const KdTree tree(p);
  std::vector<std::uint32_t> found;
  tree.within(Eigen::Vector3d(0.5, -0.25, 1.0), 2.5, found);
  std::sort(found.begin(), found.end());
  EXPECT_EQ(found, (std::vector<std::uint32_t>{0, 1, 2, 3, 4, 5}));
}

}  // namespace
}  // namespace truecut::offline::spatial
