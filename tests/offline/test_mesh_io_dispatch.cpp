#include "mesh_io_test_util.hpp"
#include "test_paths.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <functional>
#include <limits>

namespace truecut::offline {
namespace {

using test_util::expect_error;
using test_util::files_in;
using test_util::write_bytes;

TEST(MeshIoDispatch, FormatFromExtension) {
  EXPECT_EQ(format_from_extension("a/b.STL"), MeshFormat::kStl);
  EXPECT_EQ(format_from_extension("b.ply"), MeshFormat::kPly);
  EXPECT_EQ(format_from_extension("b.xyz"), MeshFormat::kXyz);
  EXPECT_EQ(format_from_extension("b.Csv"), MeshFormat::kXyz);
  EXPECT_EQ(format_from_extension("b.txt"), MeshFormat::kXyz);
  EXPECT_FALSE(format_from_extension("b.obj").has_value());
  EXPECT_FALSE(format_from_extension("stl").has_value());
}

TEST(MeshIoDispatch, ContentWinsOverTheExtension) {
  auto dir = test::scratch_dir();
  const TriangleMesh mesh = test_util::grid_mesh(4, 3);
  write_stl(dir / "binary.stl", mesh);
  std::filesystem::rename(dir / "binary.stl", dir / "binary.dat");
  EXPECT_EQ(detect_format(dir / "binary.dat"), MeshFormat::kStl);

  write_stl(dir / "ascii.stl", mesh, StlEncoding::kAscii);
  std::filesystem::rename(dir / "ascii.stl", dir / "ascii.txt");
  EXPECT_EQ(detect_format(dir / "ascii.txt"), MeshFormat::kStl);

  write_ply(dir / "mesh.ply", mesh);
  std::filesystem::rename(dir / "mesh.ply", dir / "mesh.stl");
  EXPECT_EQ(detect_format(dir / "mesh.stl"), MeshFormat::kPly);
  test_util::expect_same(read_mesh(dir / "mesh.stl"), mesh);

  write_bytes(dir / "points.pts", "# scan\n1 2 3\n4 5 6\n");
  EXPECT_EQ(detect_format(dir / "points.pts"), MeshFormat::kXyz);
  write_bytes(dir / "points.xyz", "1 2 3\n");
  EXPECT_EQ(detect_format(dir / "points.xyz"), MeshFormat::kXyz);
}

TEST(MeshIoDispatch, UnknownAndEmptyFiles) {
  auto dir = test::scratch_dir();
  write_bytes(dir / "blob.bin", std::string("\x00\x01\x02\x03\xff", 5));
  expect_error([&] { detect_format(dir / "blob.bin"); }, {"blob.bin", "unknown format", "'.bin'"});
  write_bytes(dir / "empty.ply", "");
  expect_error([&] { read_mesh(dir / "empty.ply"); }, {"empty.ply", "empty file"});
  expect_error([&] { read_mesh(dir / "absent.stl"); }, {"absent.stl", "cannot open"});
  expect_error([&] { read_mesh(dir); }, {"is a folder, not a mesh or point cloud"});
}

// Issue 23 (sweep F25): the mesh and point readers opened a FIFO (which
// blocks until a writer comes) and /dev/zero ("cannot read the file size:
// Operation not supported"); they now take the check every other reader
// makes. The test holds the FIFO's write end itself, so the old reader's
// open could not block.
TEST(MeshIoDispatch, ADeviceOrAPipeIsNotARegularFile) {
  const auto dir = test::scratch_dir();
  const std::filesystem::path fifo = dir / "scan.stl";
  ASSERT_EQ(0, ::mkfifo(fifo.c_str(), 0600));
  const int writer = ::open(fifo.c_str(), O_RDWR | O_NONBLOCK);
  ASSERT_GE(writer, 0);
  const char* says = "is not a regular file (a device, pipe or socket is read without end)";
  expect_error([&] { read_mesh(fifo); }, {"scan.stl: ", says});
  expect_error([&] { read_point_cloud(fifo); }, {"scan.stl: ", says});
  expect_error([&] { read_stl(fifo); }, {"scan.stl: ", says});
  ::close(writer);
  if (std::filesystem::exists("/dev/zero")) {
    expect_error([&] { read_mesh("/dev/zero"); }, {"/dev/zero: ", says});
    expect_error([&] { read_point_text("/dev/zero"); }, {"/dev/zero: ", says});
  }
}

TEST(MeshIoDispatch, ReadMeshAndPointCloudFromAnyFormat) {
  auto dir = test::scratch_dir();
  TriangleMesh mesh = test_util::grid_mesh(5, 4, true);
  write_mesh(dir / "m.ply", mesh);
  PointCloud cloud = read_point_cloud(dir / "m.ply");
  test_util::expect_same(cloud.points_mm, mesh.vertices_mm);
  test_util::expect_same(cloud.normals, mesh.normals);

  write_point_cloud(dir / "c.csv", cloud);
  EXPECT_EQ(test::read_file(dir / "c.csv").substr(0, 15), "x,y,z,nx,ny,nz\n");
  MeshReadReport report;
  TriangleMesh from_points = read_mesh(dir / "c.csv", {}, &report);
  EXPECT_EQ(report.format, MeshFormat::kXyz);
  EXPECT_TRUE(from_points.triangles.empty());
  test_util::expect_same(from_points.vertices_mm, mesh.vertices_mm);

  mesh.normals.clear();
  MeshWriteOptions ascii;
  ascii.ascii = true;
  ascii.comment = "nominal";
  write_mesh(dir / "m.stl", mesh, ascii);
  TriangleMesh stl = read_mesh(dir / "m.stl", {}, &report);
  EXPECT_EQ(report.encoding, "ascii");
  EXPECT_EQ(report.comments.at(0), "nominal");
  test_util::expect_same(stl, test_util::by_first_use(mesh));

  write_mesh(dir / "a.ply", mesh, ascii);
  test_util::expect_same(read_mesh(dir / "a.ply", {}, &report), mesh);
  EXPECT_EQ(report.encoding, "ascii");
}

TEST(MeshIoDispatch, WritersRefuseWhatTheFormatCannotHold) {
  auto dir = test::scratch_dir();
  const TriangleMesh mesh = test_util::grid_mesh(3, 3);
  expect_error([&] { write_mesh(dir / "m.xyz", mesh); }, {"cannot hold", "8 triangles"});
  expect_error([&] { write_mesh(dir / "m.obj", mesh); }, {"unknown output format"});
  expect_error(
      [&] {
        write_point_cloud(dir / "c.stl", PointCloud{mesh.vertices_mm, {}});
      },
      {"cannot write a point cloud"});
  TriangleMesh bad = mesh;
  bad.triangles[5][1] = 9;
  expect_error([&] { write_mesh(dir / "bad.ply", bad); }, {"triangle 5 refers to vertex 9"});
  expect_error([&] { write_mesh(dir / "bad.stl", bad); }, {"triangle 5 refers to vertex 9"});
  bad = mesh;
  bad.normals.resize(2);
  expect_error([&] { write_mesh(dir / "bad.ply", bad); }, {"2 normals for 9 vertices"});
  EXPECT_EQ(files_in(dir), 0u);
}

TEST(MeshIoAtomicWrite, MissingDirectoryLeavesNothing) {
  auto dir = test::scratch_dir();
  const TriangleMesh mesh = test_util::grid_mesh(3, 3);
  for (const char* name : {"m.stl", "m.ply", "m.xyz"}) {
    SCOPED_TRACE(name);
    const auto file = dir / "missing" / name;
    expect_error(
        [&] {
          if (format_from_extension(file) == MeshFormat::kXyz) {
            write_point_cloud(file, PointCloud{mesh.vertices_mm, {}});
          } else {
            write_mesh(file, mesh);
          }
        },
        {"cannot create", "m.", ".tmp"});
  }
  EXPECT_EQ(files_in(dir), 0u);
}

// The NaN sits far enough in that the writers have already flushed data to
// FILE.tmp when they reach it, so the clean-up path is what is tested.
TEST(MeshIoAtomicWrite, FailingWritersLeaveNoFileAndKeepTheOldOne) {
  auto dir = test::scratch_dir();
  TriangleMesh mesh = test_util::grid_mesh(600, 400, true);
  const std::size_t bad = 200000;
  mesh.vertices_mm[bad].y() = std::numeric_limits<double>::quiet_NaN();
  const PointCloud cloud{mesh.vertices_mm, mesh.normals};
  struct Case {
    const char* name;
    std::function<void(const std::filesystem::path&)> write;
  };
  const std::vector<Case> cases = {
      {"b.stl", [&](auto& f) { write_stl(f, mesh, StlEncoding::kBinary); }},
      {"a.stl", [&](auto& f) { write_stl(f, mesh, StlEncoding::kAscii); }},
      {"le.ply", [&](auto& f) { write_ply(f, mesh, PlyEncoding::kBinaryLittleEndian); }},
      {"be.ply", [&](auto& f) { write_ply(f, mesh, PlyEncoding::kBinaryBigEndian); }},
      {"a.ply", [&](auto& f) { write_ply(f, mesh, PlyEncoding::kAscii); }},
      {"c.ply", [&](auto& f) { write_ply(f, cloud); }},
      {"c.xyz", [&](auto& f) { write_point_text(f, cloud); }},
      {"c.csv",
       [&](auto& f) {
         write_point_text(f, cloud, {',', true});
       }},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const auto file = dir / c.name;
    expect_error([&] { c.write(file); }, {c.name, std::to_string(bad), "non-finite"});
    EXPECT_FALSE(std::filesystem::exists(file));
    EXPECT_FALSE(std::filesystem::exists(file.string() + ".tmp"));

    write_bytes(file, "previous content");
    expect_error([&] { c.write(file); }, {std::to_string(bad)});
    EXPECT_EQ(test::read_file(file), "previous content");
    std::filesystem::remove(file);
  }
  EXPECT_EQ(files_in(dir), 0u);

  mesh.vertices_mm[bad].y() = 1.0;
  mesh.normals[7].z() = std::numeric_limits<double>::infinity();
  expect_error([&] { write_ply(dir / "n.ply", mesh); }, {"normal of vertex 7"});
  EXPECT_EQ(files_in(dir), 0u);
}

TEST(MeshIoAtomicWrite, SuccessReplacesTheOldFileAndLeavesNoTmp) {
  auto dir = test::scratch_dir();
  write_bytes(dir / "m.stl", "previous content");
  const TriangleMesh mesh = test_util::grid_mesh(6, 5);
  write_mesh(dir / "m.stl", mesh);
  test_util::expect_same(read_mesh(dir / "m.stl"), test_util::by_first_use(mesh));
  EXPECT_EQ(files_in(dir), 1u);
}

}  // namespace
}  // namespace truecut::offline
