#include "mesh_io_test_util.hpp"
#include "test_paths.hpp"

#include <random>

namespace truecut::offline {
namespace {

using test_util::expect_error;
using test_util::write_bytes;

TEST(MeshIoPoints, WhitespaceWithCommentsAndBlankLines) {
  auto dir = test::scratch_dir();
  write_bytes(dir / "scan.xyz",
              "# exported by a scanner\n"
              "\n"
              "1 2 3\n"
              "  -4.5\t5e-1   +6   # trailing comment\r\n"
              "7 8 9");
  MeshReadReport report;
  PointCloud c = read_point_text(dir / "scan.xyz", &report);
  ASSERT_EQ(c.points_mm.size(), 3u);
  EXPECT_EQ(c.points_mm[1], Eigen::Vector3d(-4.5, 0.5, 6));
  EXPECT_EQ(c.points_mm[2], Eigen::Vector3d(7, 8, 9));
  EXPECT_FALSE(c.has_normals());
  EXPECT_EQ(report.format, MeshFormat::kXyz);
  ASSERT_EQ(report.comments.size(), 1u);
  EXPECT_EQ(report.comments[0], "exported by a scanner");
}

TEST(MeshIoPoints, SixColumnsWithoutHeaderGiveNormals) {
  auto dir = test::scratch_dir();
  write_bytes(dir / "n.txt", "0 0 1 0 0 1\n1 0 1 0.6 0 0.8\n");
  PointCloud c = read_point_text(dir / "n.txt");
  ASSERT_TRUE(c.has_normals());
  EXPECT_EQ(c.normals[1], Eigen::Vector3d(0.6, 0, 0.8));
}

TEST(MeshIoPoints, CsvHeadersMapColumnsByName) {
  auto dir = test::scratch_dir();
  write_bytes(dir / "a.csv", "x,y,z,nx,ny,nz\n1,2,3,0,0,1\n4, 5, 6, 0, 1, 0\n");
  PointCloud a = read_point_text(dir / "a.csv");
  ASSERT_EQ(a.points_mm.size(), 2u);
  EXPECT_EQ(a.points_mm[1], Eigen::Vector3d(4, 5, 6));
  EXPECT_EQ(a.normals[1], Eigen::Vector3d(0, 1, 0));

  write_bytes(dir / "b.csv", "\"id\";\"Intensity\";\"Z\";\"X\";\"Y\"\n7;0.5;3;1;2\n");
  PointCloud b = read_point_text(dir / "b.csv");
  ASSERT_EQ(b.points_mm.size(), 1u);
  EXPECT_EQ(b.points_mm[0], Eigen::Vector3d(1, 2, 3));
  EXPECT_FALSE(b.has_normals());

  write_bytes(dir / "cc.txt", "//X,Y,Z,Nx,Ny,Nz\n1,2,3,0,0,-1\n");  // CloudCompare
  PointCloud cc = read_point_text(dir / "cc.txt");
  EXPECT_EQ(cc.normals.at(0), Eigen::Vector3d(0, 0, -1));

  write_bytes(dir / "pos.csv", "a,b,c\n1,2,3\n");  // unknown names: by position
  EXPECT_EQ(read_point_text(dir / "pos.csv").points_mm.at(0), Eigen::Vector3d(1, 2, 3));

  write_bytes(dir / "header_only.csv", "x,y,z\n");
  EXPECT_TRUE(read_point_text(dir / "header_only.csv").points_mm.empty());
}

PointCloud random_cloud(std::size_t n, bool normals) {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> u(-500.0, 500.0);
  PointCloud c;
  for (std::size_t i = 0; i < n; ++i) {
    c.points_mm.emplace_back(u(rng), u(rng) * 1e-6, u(rng) * 1e9);
    if (normals) c.normals.push_back(Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized());
  }
  c.points_mm.emplace_back(0.1, -0.0, 1e-300);
  if (normals) c.normals.emplace_back(0, 0, 1);
  return c;
}

TEST(MeshIoPoints, RoundTripsAreExact) {
  auto dir = test::scratch_dir();
  for (bool normals : {false, true}) {
    const PointCloud c = random_cloud(2000, normals);
    for (PointTextFormat f :
         {PointTextFormat{' ', false}, PointTextFormat{',', true}, PointTextFormat{',', false},
          PointTextFormat{'\t', true}, PointTextFormat{';', true}}) {
      SCOPED_TRACE(std::string("separator '") + f.separator + "' header " +
                   std::to_string(f.header) + " normals " + std::to_string(normals));
      write_point_text(dir / "c.xyz", c, f);
      PointCloud back = read_point_text(dir / "c.xyz");
      test_util::expect_same(back.points_mm, c.points_mm);
      test_util::expect_same(back.normals, c.normals);
    }
  }
  EXPECT_EQ(test_util::files_in(dir), 1u);
}

TEST(MeshIoPoints, MalformedLinesAreNamed) {
  auto dir = test::scratch_dir();
  auto check = [&](const std::string& name, const std::string& text,
                   std::initializer_list<std::string_view> fragments) {
    write_bytes(dir / name, text);
    expect_error([&] { read_point_text(dir / name); }, fragments);
  };
  check("four.xyz", "# c\n1 2 3 4\n", {"four.xyz", "line 2", "4 values", "expected 3"});
  check("ragged.xyz", "1 2 3\n4 5 6\n7 8\n", {"line 3", "2 values", "first data line has 3"});
  check("ragged.csv", "x,y,z\n1,2,3\n4,5,6,7\n", {"line 3", "4 values", "header names 3"});
  check("word.xyz", "1 2 3\n4 five 6\n", {"line 2", "column 2", "'five' is not a number"});
  check("emptyfield.csv", "1,2,3\n4,,6\n", {"line 2", "column 2", "'' is not a number"});
  check("nan.xyz", "1 2 3\n\n4 nan 6\n", {"line 3", "point 1 has a non-finite coordinate"});
  check("inf.xyz", "1 2 3 0 0 1\n4 5 6 0 inf 0\n", {"line 2", "point 1 has a non-finite normal"});
  check("names.csv", "a,b,c,d\n1,2,3,4\n", {"line 1", "names no x, y, z"});
  check("empty.xyz", "", {"empty file"});
  check("comments.xyz", "# only\n\n# comments\n", {"empty file", "no points"});
}

TEST(MeshIoPoints, AnEmptyCloudCompareHeaderNamesNoColumn) {
  // Found by fuzz_mesh (tools/fuzz.sh): a line "//" alone made the reader
  // look at the first field of an empty list.
  auto dir = test::scratch_dir();
  write_bytes(dir / "cc.xyz", "//\n1 2 3\n4 5 6\n");
  EXPECT_EQ(2u, read_point_text(dir / "cc.xyz").points_mm.size());
  write_bytes(dir / "only.xyz", "//\n");
  EXPECT_THROW(read_point_text(dir / "only.xyz"), MeshIoError);
}

}  // namespace
}  // namespace truecut::offline
