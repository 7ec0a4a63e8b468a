// The cutting model gives the same result bit for bit whatever the number of
// threads that cut (DexelOptions::threads): every call's engagement, every
// dexel's height and the machined mesh (whose cusps the threads share).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "truecut/sim/benchmark_parts.hpp"
#include "truecut/sim/cutting/dexel_model.hpp"
#include "truecut/sim/cutting/swept_cut.hpp"

using namespace truecut::sim;
using namespace truecut::sim::cutting;

namespace {

bool same_bits(double a, double b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

bool same_bits(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return same_bits(a.x(), b.x()) && same_bits(a.y(), b.y()) && same_bits(a.z(), b.z());
}

bool same(const Engagement& a, const Engagement& b) {
  return same_bits(a.removed_mm3, b.removed_mm3) && same_bits(a.normal, b.normal) &&
         same_bits(a.contact_mm, b.contact_mm) && same_bits(a.axial_min_mm, b.axial_min_mm) &&
         same_bits(a.axial_max_mm, b.axial_max_mm) && a.dexels_touched == b.dexels_touched &&
         a.substeps == b.substeps && a.substeps_capped == b.substeps_capped &&
         a.invalid_input == b.invalid_input;
}

struct Move {
  CutterShape shape;
  CutterPose pose;
};

// A Ø6 ball raster through the free-form's stock along x (25 µm per cycle,
// passes 1 mm apart, the axis tilted by 0 and ±20°), then a
// bull-nose and a flat end mill across part of it: instances with thousands
// of dexels under them, which the threads share.
std::vector<Move> moves() {
  std::vector<Move> m;
  const CutterShape ball{3, 3, 20}, bull{3, 1, 20}, flat{2, 0, 20};
  for (int pass = 0; pass < 3; ++pass) {
    const double y = -6 + pass;
    const double tilt = 0.35 * (pass - 1);  // rad
    const Eigen::Vector3d axis(0, std::sin(tilt), std::cos(tilt));
    for (double x = -6; x <= 6; x += 0.025) {
      const Eigen::Vector3d n = freeform_normal(x, y);
      const Eigen::Vector3d contact(x, y, freeform_height_mm(x, y) - 0.01);
      m.push_back({ball, {contact + 3 * n - 3 * axis, axis}});
    }
  }
  for (double x = -5; x <= 5; x += 0.05)
    m.push_back({bull, {{x, -4.5, freeform_height_mm(x, -4.5) + 0.3}, {0, 0, 1}}});
  for (double x = 5; x >= -5; x -= 0.05)
    m.push_back({flat, {{x, -3, freeform_height_mm(x, -3) + 0.5}, {0, 0, 1}}});
  return m;
}

}  // namespace

TEST(CuttingThreads, SameResultWhateverTheThreadCount) {
  const BenchmarkPart part = make_part(PartId::kFreeform, {1.0, 1.0, 1.0, 2.0});
  const std::vector<Move> path = moves();
  std::vector<DexelModel> models;
  std::vector<std::vector<Engagement>> engagements;
  for (const int threads : {1, 2, 3}) {
    DexelOptions o;
    o.spacing_mm = 0.3;
    o.threads = threads;
    models.push_back(DexelModel::build(part.mesh, part.triangle_surface, part.metadata.stock, o));
    ASSERT_EQ(threads, models.back().threads());
    DexelModel& model = models.back();
    SweptCut sampler;
    std::vector<Engagement>& es = engagements.emplace_back();
    for (const Move& m : path)
      es.push_back(sampler.step(model, m.shape, m.pose));
    es.push_back(sampler.finish(model));
    // The per-cycle cut, too (several instances per call on the link moves).
    for (std::size_t k = 1; k < path.size(); k += 7)
      es.push_back(model.cut(path[k].shape, path[k - 1].pose, path[k].pose, false));
  }
  ASSERT_GT(models[0].removed_total_mm3(), 50.0) << "the path cuts";
  EXPECT_EQ(0u, models[0].thread_stats().jobs) << "one thread shares nothing";
  for (std::size_t t = 1; t < models.size(); ++t) {
    // The instances were shared between the threads, and gave the same.
    const auto stats = models[t].thread_stats();
    EXPECT_GT(stats.jobs, 200u);
    EXPECT_GT(stats.chunks, 2 * stats.jobs);
    std::printf("%d threads: %llu instances shared, %llu of %llu chunks run by helpers\n",
                models[t].threads(), static_cast<unsigned long long>(stats.jobs),
                static_cast<unsigned long long>(stats.worker_chunks),
                static_cast<unsigned long long>(stats.chunks));
    ASSERT_EQ(engagements[0].size(), engagements[t].size());
    std::size_t differing_calls = 0;
    for (std::size_t k = 0; k < engagements[0].size(); ++k)
      differing_calls += !same(engagements[0][k], engagements[t][k]);
    EXPECT_EQ(0u, differing_calls) << models[t].threads() << " threads";
    ASSERT_EQ(models[0].size(), models[t].size());
    std::size_t differing_heights = 0;
    for (std::size_t i = 0; i < models[0].size(); ++i)
      differing_heights += !same_bits(models[0].height_mm(i), models[t].height_mm(i));
    EXPECT_EQ(0u, differing_heights) << models[t].threads() << " threads";
    // The mesh's candidate edges and their cusps' bisections are shared too
    // (two jobs more).
    const auto a = models[0].machined_mesh(), b = models[t].machined_mesh();
    EXPECT_EQ(stats.jobs + 2, models[t].thread_stats().jobs)
        << "machined_mesh() shared its edges and cusps between " << models[t].threads()
        << " threads";
    ASSERT_EQ(a.vertices_mm.size(), b.vertices_mm.size());
    ASSERT_EQ(a.triangles.size(), b.triangles.size());
    std::size_t differing_vertices = 0;
    for (std::size_t i = 0; i < a.vertices_mm.size(); ++i)
      differing_vertices += !same_bits(a.vertices_mm[i], b.vertices_mm[i]);
    EXPECT_EQ(0u, differing_vertices) << models[t].threads() << " threads";
    EXPECT_TRUE(a.triangles == b.triangles);
  }
}

TEST(CuttingThreads, CopyStartsItsOwnThreads) {
  const BenchmarkPart part = make_part(PartId::kImplant, {2.0, 0.8, 1.0, 2.0});
  DexelOptions o;
  o.threads = 2;
  const DexelModel a = DexelModel::build(part.mesh, part.triangle_surface, part.metadata.stock, o);
  DexelModel b = a;
  EXPECT_EQ(2, b.threads());
  const CutterShape flat{2, 0, 20};
  const Engagement e = b.cut(flat, {{-6, 0, 16.5}, {0, 0, 1}}, {{6, 0, 16.5}, {0, 0, 1}});
  EXPECT_GT(e.removed_mm3, 1.0);
  EXPECT_EQ(0.0, a.removed_total_mm3()) << "the original is untouched";
}

TEST(CuttingThreads, ThreadCountIsChecked) {
  const BenchmarkPart part = make_part(PartId::kImplant, {2.0, 0.8, 1.0, 2.0});
  DexelOptions o;
  o.threads = -1;
  EXPECT_THROW(DexelModel::build(part.mesh, part.triangle_surface, part.metadata.stock, o),
               std::invalid_argument);
  o.threads = 0;  // one per hardware thread
  EXPECT_GE(DexelModel::build(part.mesh, part.triangle_surface, part.metadata.stock, o).threads(),
            1);
}
