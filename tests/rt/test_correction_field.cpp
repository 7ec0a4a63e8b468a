#include "truecut/rt/core/correction_field.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>
#include <stdexcept>
#include <utility>

namespace truecut::rt {
namespace {

static_assert(noexcept(
    std::declval<const CorrectionField&>().evaluate(0, std::declval<const Eigen::Vector3d&>())));
static_assert(noexcept(std::declval<const CorrectionField&>().evaluate_trilinear(
    0, std::declval<const Eigen::Vector3d&>())));

// Dyadic origin and spacing keep node positions exact.
FieldGrid test_grid() {
  FieldGrid g;
  g.origin_mm = {-12.5, 3.0, -40.0};
  g.spacing_mm = {2.5, 0.5, 1.25};
  g.dims = {7, 6, 5};
  return g;
}

using NodeFn = std::function<FieldNode(const Eigen::Vector3d&)>;

FieldLayer layer_from(const FieldGrid& g, int32_t tool, const NodeFn& fn) {
  FieldLayer layer{tool, {}};
  for (int32_t k = 0; k < g.dims[2]; ++k)
    for (int32_t j = 0; j < g.dims[1]; ++j)
      for (int32_t i = 0; i < g.dims[0]; ++i)
        layer.nodes.push_back(fn(g.node_position_mm(i, j, k)));
  return layer;
}

FieldLayer random_layer(const FieldGrid& g, int32_t tool, std::mt19937_64& rng,
                        bool random_weights) {
  std::uniform_real_distribution<double> d(-0.2, 0.2), w(0.0, 1.0);
  return layer_from(g, tool, [&](const Eigen::Vector3d&) {
    return FieldNode{d(rng), d(rng), d(rng), random_weights ? w(rng) : 1.0};
  });
}

Eigen::Vector3d random_inside(const FieldGrid& g, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Eigen::Vector3d p;
  for (int a = 0; a < 3; ++a)
    p[a] = g.origin_mm[a] + unit(rng) * (g.dims[a] - 1) * g.spacing_mm[a];
  return p;
}

TEST(CorrectionField, GridNodesReproduceTheStoredVectors) {
  std::mt19937_64 rng(1);
  const FieldGrid g = test_grid();
  const CorrectionField field(g, {random_layer(g, 3, rng, false)});
  const auto nodes = field.nodes(3);
  ASSERT_EQ(static_cast<int64_t>(nodes.size()), g.node_count());
  for (int32_t k = 0; k < g.dims[2]; ++k)
    for (int32_t j = 0; j < g.dims[1]; ++j)
      for (int32_t i = 0; i < g.dims[0]; ++i) {
        const FieldNode& n = nodes[g.index(i, j, k)];
        const FieldSample s = field.evaluate(3, g.node_position_mm(i, j, k));
        ASSERT_EQ(s.status, FieldStatus::kOk) << i << " " << j << " " << k;
        EXPECT_NEAR(s.correction_mm.x(), n.dx_mm, 1e-12) << i << " " << j << " " << k;
        EXPECT_NEAR(s.correction_mm.y(), n.dy_mm, 1e-12) << i << " " << j << " " << k;
        EXPECT_NEAR(s.correction_mm.z(), n.dz_mm, 1e-12) << i << " " << j << " " << k;
        EXPECT_NEAR(s.weight, 1.0, 1e-15);
      }
}

TEST(CorrectionField, NodesAreInterpolatedWhateverTheWeight) {
  std::mt19937_64 rng(2);
  const FieldGrid g = test_grid();
  const CorrectionField field(g, {random_layer(g, 0, rng, true)});
  const auto nodes = field.nodes(0);
  for (int32_t k = 0; k < g.dims[2]; ++k)
    for (int32_t j = 0; j < g.dims[1]; ++j)
      for (int32_t i = 0; i < g.dims[0]; ++i) {
        const FieldNode& n = nodes[g.index(i, j, k)];
        const FieldSample s = field.evaluate(0, g.node_position_mm(i, j, k));
        EXPECT_LE((s.vector_mm - Eigen::Vector3d(n.dx_mm, n.dy_mm, n.dz_mm)).norm(), 1e-12);
        EXPECT_LE((s.correction_mm - s.weight * s.vector_mm).norm(), 1e-15);
      }
}

TEST(CorrectionField, LinearFieldsAreReproducedExactlyWithTheirJacobian) {
  Eigen::Matrix3d m;
  m << 0.001, -0.002, 0.0005, 0.003, 0.0001, -0.001, -0.0007, 0.0004, 0.002;
  const Eigen::Vector3d b{0.01, -0.02, 0.005};
  const FieldGrid g = test_grid();
  const NodeFn linear = [&](const Eigen::Vector3d& p) {
    const Eigen::Vector3d d = m * p + b;
    return FieldNode{d.x(), d.y(), d.z(), 1.0};
  };
  const CorrectionField field(g, {layer_from(g, 1, linear)});
  std::mt19937_64 rng(3);
  for (int n = 0; n < 2000; ++n) {
    const Eigen::Vector3d p = random_inside(g, rng);
    for (const FieldSample& s : {field.evaluate_tricubic(1, p), field.evaluate_trilinear(1, p)}) {
      ASSERT_EQ(s.status, FieldStatus::kOk);
      EXPECT_LE((s.correction_mm - (m * p + b)).cwiseAbs().maxCoeff(), 1e-13);
      EXPECT_LE((s.jacobian - m).cwiseAbs().maxCoeff(), 1e-13);
    }
  }
}

TEST(CorrectionField, SmoothFieldIsApproximatedBetterThanTrilinear) {
  FieldGrid g;
  g.origin_mm = {0, 0, 0};
  g.spacing_mm = {5, 5, 5};
  g.dims = {13, 13, 13};
  auto exact = [](const Eigen::Vector3d& p) {
    return Eigen::Vector3d(0.05 * std::sin(p.x() / 12.0),
                           0.03 * std::cos(p.y() / 9.0) * std::sin(p.z() / 15.0),
                           0.02 * std::sin((p.x() + p.y()) / 20.0));
  };
  const CorrectionField field(g, {layer_from(g, 1, [&](const Eigen::Vector3d& p) {
                                const Eigen::Vector3d d = exact(p);
                                return FieldNode{d.x(), d.y(), d.z(), 1.0};
                              })});
  // Away from the faces, where the natural end conditions cost accuracy.
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> inner(10.0, 50.0);
  double cubic_max = 0, linear_max = 0;
  for (int n = 0; n < 2000; ++n) {
    const Eigen::Vector3d p{inner(rng), inner(rng), inner(rng)};
    cubic_max =
        std::max(cubic_max, (field.evaluate_tricubic(1, p).correction_mm - exact(p)).norm());
    linear_max =
        std::max(linear_max, (field.evaluate_trilinear(1, p).correction_mm - exact(p)).norm());
  }
  EXPECT_LT(cubic_max, 1e-4) << "trilinear " << linear_max;
  EXPECT_LT(cubic_max, 0.05 * linear_max) << "trilinear " << linear_max;
}

// Largest jump of value and Jacobian across cell faces, probed at +-1e-9 cell.
std::pair<double, double> largest_jumps_across_faces(
    const CorrectionField& field,
    FieldSample (CorrectionField::*eval)(int32_t, const Eigen::Vector3d&) const noexcept) {
  const FieldGrid& g = field.grid();
  std::mt19937_64 rng(5);
  std::uniform_int_distribution<int> axis_pick(0, 2);
  double value_jump = 0, jacobian_jump = 0;
  for (int n = 0; n < 3000; ++n) {
    Eigen::Vector3d p = random_inside(g, rng);
    const int a = axis_pick(rng);
    std::uniform_int_distribution<int32_t> face(1, g.dims[a] - 2);
    p[a] = g.origin_mm[a] + face(rng) * g.spacing_mm[a];
    Eigen::Vector3d lo = p, hi = p;
    lo[a] -= 1e-9 * g.spacing_mm[a];
    hi[a] += 1e-9 * g.spacing_mm[a];
    const FieldSample sl = (field.*eval)(0, lo), sh = (field.*eval)(0, hi);
    EXPECT_EQ(sl.status, FieldStatus::kOk);
    EXPECT_EQ(sh.status, FieldStatus::kOk);
    value_jump = std::max(value_jump, (sl.correction_mm - sh.correction_mm).cwiseAbs().maxCoeff());
    jacobian_jump = std::max(jacobian_jump, (sl.jacobian - sh.jacobian).cwiseAbs().maxCoeff());
  }
  return {value_jump, jacobian_jump};
}

TEST(CorrectionField, ValueAndGradientAreContinuousAcrossCellFaces) {
  std::mt19937_64 rng(6);
  const FieldGrid g = test_grid();
  const CorrectionField field(g, {random_layer(g, 0, rng, true)});
  const auto [value_jump, jacobian_jump] =
      largest_jumps_across_faces(field, &CorrectionField::evaluate_tricubic);
  EXPECT_LT(value_jump, 1e-9);
  EXPECT_LT(jacobian_jump, 1e-7);
  // The same probe sees the trilinear baseline's kinks.
  const auto [lin_value_jump, lin_jacobian_jump] =
      largest_jumps_across_faces(field, &CorrectionField::evaluate_trilinear);
  EXPECT_LT(lin_value_jump, 1e-9);
  EXPECT_GT(lin_jacobian_jump, 1e-3);
}

TEST(CorrectionField, JacobianMatchesFiniteDifferences) {
  std::mt19937_64 rng(7);
  const FieldGrid g = test_grid();
  const CorrectionField field(g, {random_layer(g, 0, rng, true)});
  for (int n = 0; n < 500; ++n) {
    Eigen::Vector3d p = random_inside(g, rng);
    for (int a = 0; a < 3; ++a)  // keep the +-h probe inside
      p[a] = std::clamp(p[a], g.origin_mm[a] + 1e-3,
                        g.origin_mm[a] + (g.dims[a] - 1) * g.spacing_mm[a] - 1e-3);
    const FieldSample s = field.evaluate(0, p);
    for (int a = 0; a < 3; ++a) {
      const double h = 1e-5;
      Eigen::Vector3d lo = p, hi = p;
      lo[a] -= h;
      hi[a] += h;
      const Eigen::Vector3d fd =
          (field.evaluate(0, hi).correction_mm - field.evaluate(0, lo).correction_mm) / (2 * h);
      EXPECT_LE((s.jacobian.col(a) - fd).cwiseAbs().maxCoeff(), 1e-6) << "axis " << a;
    }
  }
}

TEST(CorrectionField, WeightStaysInUnitIntervalWithoutOvershoot) {
  // A hard 0/1 step in the node weights would make an interpolating spline ring.
  const FieldGrid g = test_grid();
  const CorrectionField field(g, {layer_from(g, 0, [&](const Eigen::Vector3d& p) {
                                return FieldNode{0.1, 0.0, 0.0, p.x() < 0.0 ? 0.0 : 1.0};
                              })});
  std::mt19937_64 rng(8);
  for (int n = 0; n < 5000; ++n) {
    const FieldSample s = field.evaluate(0, random_inside(g, rng));
    ASSERT_GE(s.weight, 0.0);
    ASSERT_LE(s.weight, 1.0);
    ASSERT_LE(s.correction_mm.x(), 0.1 + 1e-15);
  }
}

TEST(CorrectionField, ZeroWeightRimFadesSmoothlyToZeroAtTheGridFaces) {
  FieldGrid g;
  g.origin_mm = {0, 0, 0};
  g.spacing_mm = {1, 2, 4};
  g.dims = {8, 8, 8};
  auto on_rim = [&](const Eigen::Vector3d& p) {
    for (int a = 0; a < 3; ++a) {
      const double t = p[a] / g.spacing_mm[a];
      if (t < 1.5 || t > g.dims[a] - 2.5) return true;  // two outermost node layers
    }
    return false;
  };
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> d(-0.2, 0.2);
  const CorrectionField field(g, {layer_from(g, 0, [&](const Eigen::Vector3d& p) {
                                return FieldNode{d(rng), d(rng), d(rng), on_rim(p) ? 0.0 : 1.0};
                              })});
  for (int n = 0; n < 2000; ++n) {
    Eigen::Vector3d p = random_inside(g, rng);
    const int a = n % 3;
    const double face = (n / 3) % 2 == 0 ? 0.0 : (g.dims[a] - 1) * g.spacing_mm[a];
    p[a] = face + (face == 0.0 ? 1e-9 : -1e-9);
    const FieldSample inside = field.evaluate(0, p);
    ASSERT_EQ(inside.status, FieldStatus::kOk);
    EXPECT_LT(inside.correction_mm.cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LT(inside.jacobian.cwiseAbs().maxCoeff(), 1e-9);
  }
  // Well inside the rim the full correction applies.
  const FieldSample centre = field.evaluate(0, g.node_position_mm(4, 4, 4));
  EXPECT_NEAR(centre.weight, 1.0, 1e-15);
}

TEST(CorrectionField, AnInvalidNodeContributesNothingAndFadesByDistance) {
  // Issue 19, point 3: one isolated invalid node (weight 0) whose stored
  // vector is far from its neighbours'. Its own value must not appear
  // anywhere, its weight is 0, and the weight fades by the distance to it
  // (full at the next node) instead of taking 0.70 of a smoothed weight.
  const FieldGrid g = test_grid();
  const Eigen::Vector3d bad = g.node_position_mm(3, 3, 2);
  const CorrectionField field(
      g, {layer_from(g, 0, [&](const Eigen::Vector3d& p) {
        return p == bad ? FieldNode{5.0, -4.0, 3.0, 0.0} : FieldNode{0.1, 0.0, 0.0, 1.0};
      })});
  const FieldSample at = field.evaluate(0, bad);
  ASSERT_EQ(at.status, FieldStatus::kOk);
  EXPECT_EQ(0.0, at.weight);
  EXPECT_EQ(Eigen::Vector3d::Zero(), at.correction_mm);
  // Near it the correction is the neighbours' 0.1 mm along x, weighted:
  // nothing of (5, -4, 3).
  std::mt19937_64 rng(19);
  std::uniform_real_distribution<double> near(-1.5, 1.5);
  for (int n = 0; n < 5000; ++n) {
    const Eigen::Vector3d p =
        bad + g.spacing_mm.cwiseProduct(Eigen::Vector3d(near(rng), near(rng), near(rng)));
    const FieldSample s = field.evaluate(0, p);
    ASSERT_EQ(s.status, FieldStatus::kOk);
    ASSERT_NEAR(0.1 * s.weight, s.correction_mm.x(), 1e-12) << p.transpose();
    ASSERT_NEAR(0.0, s.correction_mm.tail<2>().norm(), 1e-12) << p.transpose();
  }
  // The weight by distance: 0 at the node, 1/2 halfway to a neighbour, 1 at
  // every neighbouring node.
  for (int a = 0; a < 3; ++a) {
    Eigen::Vector3d e = Eigen::Vector3d::Zero();
    e[a] = g.spacing_mm[a];
    EXPECT_NEAR(0.5, field.evaluate(0, bad + 0.5 * e).weight, 1e-15) << a;
    EXPECT_EQ(1.0, field.evaluate(0, bad + e).weight) << a;
    EXPECT_EQ(1.0, field.evaluate(0, bad - e).weight) << a;
  }
  EXPECT_EQ(1.0, field.evaluate(0, g.node_position_mm(4, 4, 3)).weight);
  EXPECT_GT(field.evaluate(0, bad + 0.1 * g.spacing_mm).weight, 0.0);
}

TEST(CorrectionField, OutsideTheGridGivesZeroAndAStatus) {
  std::mt19937_64 rng(10);
  const FieldGrid g = test_grid();
  const CorrectionField field(g, {random_layer(g, 0, rng, false)});
  const Eigen::Vector3d far_corner =
      g.origin_mm +
      g.spacing_mm.cwiseProduct(Eigen::Vector3d(g.dims[0] - 1, g.dims[1] - 1, g.dims[2] - 1));
  EXPECT_TRUE(field.inside(g.origin_mm));
  EXPECT_TRUE(field.inside(far_corner));
  EXPECT_EQ(field.evaluate(0, far_corner).status, FieldStatus::kOk);
  for (int a = 0; a < 3; ++a) {
    for (const double step : {-1e-6, 1e-6}) {
      Eigen::Vector3d p = step < 0 ? g.origin_mm : far_corner;
      p[a] += step;
      EXPECT_FALSE(field.inside(p));
      for (const FieldSample& s : {field.evaluate_tricubic(0, p), field.evaluate_trilinear(0, p)}) {
        EXPECT_EQ(s.status, FieldStatus::kOutsideGrid);
        EXPECT_EQ(s.correction_mm, Eigen::Vector3d::Zero());
        EXPECT_EQ(s.weight, 0.0);
        EXPECT_EQ(s.jacobian, Eigen::Matrix3d::Zero());
      }
    }
  }
}

TEST(CorrectionField, OneLayerPerTool) {
  const FieldGrid g = test_grid();
  auto constant = [&](int32_t tool, double dz) {
    return layer_from(g, tool, [=](const Eigen::Vector3d&) { return FieldNode{0, 0, dz, 1}; });
  };
  const CorrectionField field(g, {constant(12, 0.03), constant(2, -0.01), constant(7, 0.02)});
  ASSERT_EQ(field.tools().size(), 3u);
  EXPECT_EQ(field.tools()[0], 2);
  EXPECT_EQ(field.tools()[2], 12);
  const Eigen::Vector3d p = g.node_position_mm(2, 2, 2) + Eigen::Vector3d(0.3, 0.1, 0.2);
  EXPECT_NEAR(field.evaluate(2, p).correction_mm.z(), -0.01, 1e-15);
  EXPECT_NEAR(field.evaluate(7, p).correction_mm.z(), 0.02, 1e-15);
  EXPECT_NEAR(field.evaluate(12, p).correction_mm.z(), 0.03, 1e-15);
  const FieldSample missing = field.evaluate(5, p);
  EXPECT_EQ(missing.status, FieldStatus::kNoLayerForTool);
  EXPECT_EQ(missing.correction_mm, Eigen::Vector3d::Zero());
  EXPECT_EQ(missing.weight, 0.0);
  EXPECT_TRUE(field.nodes(5).empty());
}

TEST(CorrectionField, NonFinitePositionIsRejected) {
  std::mt19937_64 rng(11);
  const FieldGrid g = test_grid();
  const CorrectionField field(g, {random_layer(g, 0, rng, false)});
  for (const double bad : {std::nan(""), HUGE_VAL, -HUGE_VAL}) {
    const FieldSample s = field.evaluate(0, Eigen::Vector3d(0, bad, -38));
    EXPECT_EQ(s.status, FieldStatus::kNonFinite);
    EXPECT_EQ(s.correction_mm, Eigen::Vector3d::Zero());
  }
}

TEST(CorrectionField, EvaluateFollowsTheDeclaredInterpolation) {
  std::mt19937_64 rng(12);
  const FieldGrid g = test_grid();
  const FieldLayer layer = random_layer(g, 0, rng, true);
  const CorrectionField cubic(g, {layer});
  const CorrectionField linear(g, {layer}, FieldInterpolation::kTrilinear);
  const Eigen::Vector3d p = random_inside(g, rng);
  EXPECT_EQ(cubic.evaluate(0, p).correction_mm, cubic.evaluate_tricubic(0, p).correction_mm);
  EXPECT_EQ(linear.evaluate(0, p).correction_mm, linear.evaluate_trilinear(0, p).correction_mm);
  EXPECT_NE(cubic.evaluate(0, p).correction_mm, linear.evaluate(0, p).correction_mm);
}

TEST(CorrectionField, TrilinearBaselineAveragesTheCellCorners) {
  std::mt19937_64 rng(13);
  const FieldGrid g = test_grid();
  const CorrectionField field(g, {random_layer(g, 0, rng, true)});
  const auto nodes = field.nodes(0);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double weight_sum = 0;
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) {
        const FieldNode& n = nodes[g.index(3 + i, 2 + j, 1 + k)];
        sum += Eigen::Vector3d(n.dx_mm, n.dy_mm, n.dz_mm);
        weight_sum += n.weight;
      }
  const FieldSample s =
      field.evaluate_trilinear(0, g.node_position_mm(3, 2, 1) + 0.5 * g.spacing_mm);
  EXPECT_LE((s.vector_mm - sum / 8).norm(), 1e-15);
  EXPECT_NEAR(s.weight, weight_sum / 8, 1e-15);
}

TEST(CorrectionField, ConstructionRejectsBadData) {
  std::mt19937_64 rng(14);
  const FieldGrid g = test_grid();
  const FieldLayer good = random_layer(g, 0, rng, false);
  auto expect_invalid = [](const FieldGrid& grid, std::vector<FieldLayer> layers,
                           const std::string& fragment) {
    try {
      CorrectionField field(grid, std::move(layers));
      ADD_FAILURE() << "accepted; expected an error mentioning '" << fragment << "'";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
  };
  FieldGrid flat = g;
  flat.dims[2] = 1;
  expect_invalid(flat, {good}, "dims z");
  FieldGrid negative = g;
  negative.spacing_mm.y() = -1;
  expect_invalid(negative, {good}, "spacing y");
  expect_invalid(g, {}, "no layers");
  FieldLayer short_layer = good;
  short_layer.nodes.pop_back();
  expect_invalid(g, {short_layer}, "nodes, grid has");
  FieldLayer nan_layer = good;
  nan_layer.nodes[17].dy_mm = std::nan("");
  expect_invalid(g, {nan_layer}, "non-finite vector at node index 17");
  FieldLayer heavy = good;
  heavy.nodes[3].weight = 1.5;
  expect_invalid(g, {heavy}, "outside [0, 1]");
  expect_invalid(g, {good, good}, "two layers for tool 0");
  FieldLayer negative_tool = good;
  negative_tool.tool = -1;
  expect_invalid(g, {negative_tool}, "tool number");
}

}  // namespace
}  // namespace truecut::rt
