#include "test_paths.hpp"
#include "truecut/offline/compensation_matrix.hpp"
#include "truecut/offline/mesh_io.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

namespace truecut::offline {
namespace {

std::string read_text(const std::filesystem::path& f) {
  std::ifstream in(f);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

CompensationPoints three_points() {
  CompensationPoints c;
  c.positions_mm = {{1, 2, 3}, {0.1, -0.2, 1e-3}, {5, 5, 5}};
  c.normals = {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}};
  c.surface_ids = {4, 7, 4};
  c.triangles = {0, 1, 2};
  return c;
}

ErrorVectors errors_for_three() {
  ErrorVectors e;
  e.vectors_mm = {{0, 0, 0.125}, {-0.03, 0, 0}, {0, 0, 0}};
  e.status = {ErrorStatus::kValid, ErrorStatus::kValid, ErrorStatus::kNoHit};
  e.normal_mm = {0.125, -0.03, 0};
  return e;
}

TEST(CompensationMatrix, MirrorNegatesValidErrorsAndZeroesInvalidOnes) {
  const CompensationMatrix m = mirror(three_points(), errors_for_three());
  ASSERT_EQ(m.size(), 3u);
  EXPECT_EQ(m.vectors_mm[0], Eigen::Vector3d(0, 0, -0.125));
  EXPECT_EQ(m.vectors_mm[1], Eigen::Vector3d(0.03, 0, 0));
  EXPECT_EQ(m.vectors_mm[2], Eigen::Vector3d::Zero());
  EXPECT_EQ(m.valid, (std::vector<std::uint8_t>{1, 1, 0}));
  EXPECT_EQ(m.surface_ids, (std::vector<std::int32_t>{4, 7, 4}));
  EXPECT_THROW(mirror(three_points(), ErrorVectors{}), std::invalid_argument);
}

TEST(CompensationMatrix, CsvIsExactAndDocumented) {
  const auto dir = test::scratch_dir();
  const auto file = dir / "compensation_matrix.csv";
  write_compensation_matrix(file, mirror(three_points(), errors_for_three()),
                            "nominal part.stl\nscan scan.ply");
  EXPECT_EQ(read_text(file),
            "# truecut compensation matrix v1\n"
            "# frame: workpiece\n"
            "# units: mm\n"
            "# dx,dy,dz: compensation vector = -(measured - nominal); 0 where valid = 0\n"
            "# nominal part.stl\n"
            "# scan scan.ply\n"
            "x,y,z,dx,dy,dz,valid,surface_id\n"
            "1,2,3,0,0,-0.125,1,4\n"
            "0.1,-0.2,0.001,0.03,0,0,1,7\n"
            "5,5,5,0,0,0,0,4\n");
  EXPECT_FALSE(std::filesystem::exists(dir / "compensation_matrix.csv.tmp"));
  // The point readers take it too: comments skipped, x, y, z by name.
  const PointCloud back = read_point_cloud(file);
  EXPECT_EQ(back.points_mm, three_points().positions_mm);
}

TEST(CompensationMatrix, FailedWriteLeavesTheOldFileAlone) {
  const auto dir = test::scratch_dir();
  const auto file = dir / "m.csv";
  { std::ofstream(file) << "old\n"; }
  CompensationMatrix bad = mirror(three_points(), errors_for_three());
  bad.vectors_mm[1].x() = std::nan("");
  EXPECT_THROW(write_compensation_matrix(file, bad), MeshIoError);
  EXPECT_EQ(read_text(file), "old\n");
  EXPECT_FALSE(std::filesystem::exists(dir / "m.csv.tmp"));
  EXPECT_THROW(write_compensation_matrix(dir / "no" / "such" / "m.csv",
                                         mirror(three_points(), errors_for_three())),
               MeshIoError);
}

}  // namespace
}  // namespace truecut::offline
