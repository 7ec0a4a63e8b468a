#include "mesh_io_test_util.hpp"
#include "test_paths.hpp"

#include <cmath>
#include <limits>

namespace truecut::offline {
namespace {

using test_util::expect_error;
using test_util::put;
using test_util::write_bytes;

TriangleMesh read(const std::filesystem::path& file, MeshReadReport* report = nullptr) {
  return read_ply(file, {}, report);
}

TEST(MeshIoPly, AsciiWithExtraPropertiesListsElementsAndPolygons) {
  auto dir = test::scratch_dir();
  write_bytes(dir / "scan.ply",
              "ply\n"
              "format ascii 1.0\n"
              "comment made by hand\n"
              "obj_info scanner XYZ-1\n"
              "element vertex 5\n"
              "property float x\nproperty float y\nproperty float z\n"
              "property uchar red\n"
              "property list uchar int neighbours\n"
              "property float nx\nproperty float ny\nproperty float nz\n"
              "element edge 1\nproperty int vertex1\nproperty int vertex2\n"
              "element face 3\n"
              "property uchar flags\n"
              "property list uchar int vertex_indices\n"
              "property list uchar float texcoord\n"
              "element material 2\nproperty list ushort double params\nproperty int id\n"
              "end_header\n"
              "0 0 0 255 2 1 2 0 0 1\n"
              "1 0 0 10 0 0 0 1\n"
              "1 1 0 20 1 0 0 0 1\n"
              "0 1 0 30 3 0 1 2 0 0 1\n"
              "0.5 0.5 1 40 0 0.25 -0.5 0.75\n"
              "\n"
              "0 1\n"
              "7 3 0 1 2 6 0 0 1 0 1 1\n"
              "8 4 0 1 2 3 0\n"
              "9 5 0 1 4 2 3 1 0.5\n"
              "2 1.5 2.5 11\n"
              "0 12\n");
  MeshReadReport report;
  TriangleMesh m = read(dir / "scan.ply", &report);
  EXPECT_EQ(report.encoding, "ascii");
  ASSERT_EQ(m.vertices_mm.size(), 5u);
  EXPECT_EQ(m.vertices_mm[4], Eigen::Vector3d(0.5, 0.5, 1));
  ASSERT_TRUE(m.has_normals());
  EXPECT_EQ(m.normals[4], Eigen::Vector3d(0.25, -0.5, 0.75));
  const std::vector<Triangle> expected = {{0, 1, 2}, {0, 1, 2}, {0, 2, 3},
                                          {0, 1, 4}, {0, 4, 2}, {0, 2, 3}};
  EXPECT_EQ(m.triangles, expected);
  EXPECT_EQ(report.faces_in_file, 3u);
  EXPECT_EQ(report.polygons_triangulated, 2u);
  ASSERT_EQ(report.comments.size(), 2u);
  EXPECT_EQ(report.comments[0], "made by hand");
  EXPECT_EQ(report.comments[1], "obj_info scanner XYZ-1");
}

// Mixed coordinate types, an int list count named vertex_index, a list to
// skip on faces, CRLF header lines.
TEST(MeshIoPly, BinaryLittleEndianHandWritten) {
  auto dir = test::scratch_dir();
  std::string s =
      "ply\r\nformat binary_little_endian 1.0\r\ncomment little\r\n"
      "element vertex 4\r\n"
      "property short x\r\nproperty double y\r\nproperty float z\r\nproperty uchar quality\r\n"
      "property float nx\r\nproperty float ny\r\nproperty float nz\r\n"
      "element face 2\r\n"
      "property list int uint vertex_index\r\nproperty list uchar int extra\r\n"
      "end_header\r\n";
  const double ys[4] = {0.1, 0.1, 3.3, 3.3};
  const std::int16_t xs[4] = {0, 2, 2, 0};
  for (int i = 0; i < 4; ++i) {
    put<std::int16_t>(s, xs[i]);
    put<double>(s, ys[i]);
    put<float>(s, 0.5f);
    put<std::uint8_t>(s, 200);
    put<float>(s, 0.0f);
    put<float>(s, 0.0f);
    put<float>(s, -1.0f);
  }
  for (const auto& f : {std::array<std::uint32_t, 3>{0, 1, 2}, {0, 2, 3}}) {
    put<std::int32_t>(s, 3);
    for (auto v : f)
      put<std::uint32_t>(s, v);
    put<std::uint8_t>(s, 2);
    put<std::int32_t>(s, -7);
    put<std::int32_t>(s, 9);
  }
  write_bytes(dir / "le.ply", s);
  MeshReadReport report;
  TriangleMesh m = read(dir / "le.ply", &report);
  EXPECT_EQ(report.encoding, "binary_little_endian");
  ASSERT_EQ(m.vertices_mm.size(), 4u);
  EXPECT_EQ(m.vertices_mm[1], Eigen::Vector3d(2, 0.1, 0.5));
  EXPECT_EQ(m.vertices_mm[3], Eigen::Vector3d(0, 3.3, 0.5));
  EXPECT_EQ(m.normals[2], Eigen::Vector3d(0, 0, -1));
  EXPECT_EQ(m.triangles, (std::vector<Triangle>{{0, 1, 2}, {0, 2, 3}}));
}

// Faces before vertices, a list on the vertex element, a quad.
TEST(MeshIoPly, BinaryBigEndianHandWritten) {
  auto dir = test::scratch_dir();
  std::string s =
      "ply\nformat binary_big_endian 1.0\n"
      "element face 1\nproperty list uchar int vertex_indices\n"
      "element vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
      "property list uchar ushort adjacent\n"
      "end_header\n";
  put<std::uint8_t>(s, 4, true);
  for (std::int32_t v : {0, 1, 2, 3})
    put<std::int32_t>(s, v, true);
  const float xyz[4][3] = {{0, 0, 0}, {1.5f, 0, 0}, {1.5f, 2.25f, 0}, {0, 2.25f, -1e-3f}};
  for (int i = 0; i < 4; ++i) {
    for (float c : xyz[i])
      put<float>(s, c, true);
    put<std::uint8_t>(s, static_cast<std::uint8_t>(i), true);
    for (int k = 0; k < i; ++k)
      put<std::uint16_t>(s, static_cast<std::uint16_t>(k), true);
  }
  write_bytes(dir / "be.ply", s);
  MeshReadReport report;
  TriangleMesh m = read(dir / "be.ply", &report);
  EXPECT_EQ(report.encoding, "binary_big_endian");
  ASSERT_EQ(m.vertices_mm.size(), 4u);
  EXPECT_EQ(m.vertices_mm[2], Eigen::Vector3d(1.5, 2.25, 0));
  EXPECT_EQ(m.vertices_mm[3], Eigen::Vector3d(0, 2.25, static_cast<double>(-1e-3f)));
  EXPECT_FALSE(m.has_normals());
  EXPECT_EQ(m.triangles, (std::vector<Triangle>{{0, 1, 2}, {0, 2, 3}}));
  EXPECT_EQ(report.polygons_triangulated, 1u);
}

TriangleMesh precise_mesh() {
  TriangleMesh m = test_util::grid_mesh(23, 17, true);
  for (auto& v : m.vertices_mm)
    v += Eigen::Vector3d(0.1, 1.0 / 3.0, -1e-7);
  return m;
}

TEST(MeshIoPly, RoundTripEveryEncoding) {
  auto dir = test::scratch_dir();
  const TriangleMesh mesh = precise_mesh();
  TriangleMesh bare = mesh;
  bare.normals.clear();
  for (auto enc :
       {PlyEncoding::kBinaryLittleEndian, PlyEncoding::kBinaryBigEndian, PlyEncoding::kAscii}) {
    SCOPED_TRACE(static_cast<int>(enc));
    write_ply(dir / "m.ply", mesh, enc, "round trip\nsecond line");
    MeshReadReport report;
    test_util::expect_same(read(dir / "m.ply", &report), mesh);
    EXPECT_EQ(report.comments.back(), "round trip second line");
    write_ply(dir / "bare.ply", bare, enc);
    test_util::expect_same(read(dir / "bare.ply"), bare);

    const PointCloud cloud{mesh.vertices_mm, mesh.normals};
    write_ply(dir / "c.ply", cloud, enc);
    TriangleMesh back = read(dir / "c.ply");
    EXPECT_TRUE(back.triangles.empty());
    test_util::expect_same(back.vertices_mm, cloud.points_mm);
    test_util::expect_same(back.normals, cloud.normals);
  }
  EXPECT_EQ(test_util::files_in(dir), 3u);  // no .tmp left behind
}

const std::string kAsciiHead =
    "ply\nformat ascii 1.0\nelement vertex 4\n"
    "property double x\nproperty double y\nproperty double z\n"
    "element face 2\nproperty list uchar int vertex_indices\nend_header\n";
const std::string kAsciiVertices = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n";

TEST(MeshIoPly, AsciiCountsThatDoNotMatch) {
  auto dir = test::scratch_dir();
  write_bytes(dir / "short.ply",
              "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
              "property float z\nend_header\n0 0 0\n1 0 0\n1 1 0\n");
  expect_error([&] { read(dir / "short.ply"); }, {"short.ply", "ends at vertex 3 of 4"});
  write_bytes(dir / "faces.ply", kAsciiHead + "0 0 0\n1 0 0\n1 1 0\n3 0 1 2\n3 0 2 1\n");
  expect_error([&] { read(dir / "faces.ply"); },
               {"vertex 3 (line 13)", "4 values, more than the header declares"});
  write_bytes(dir / "more.ply", kAsciiHead + kAsciiVertices + "3 0 1 2\n3 0 2 3\n3 1 2 3\n");
  expect_error([&] { read(dir / "more.ply"); }, {"line 16", "after the last element"});
  write_bytes(dir / "few.ply", kAsciiHead + kAsciiVertices + "3 0 1 2\n3 0 2\n");
  expect_error([&] { read(dir / "few.ply"); }, {"face 1 (line 15)", "fewer values"});
}

TEST(MeshIoPly, NonFiniteVerticesAreNamed) {
  auto dir = test::scratch_dir();
  write_bytes(dir / "nan.ply", kAsciiHead + "0 0 0\n1 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n3 0 2 3\n");
  expect_error([&] { read(dir / "nan.ply"); }, {"vertex 2 has a non-finite coordinate", "nan"});

  std::string s =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nend_header\n";
  for (int i = 0; i < 9; ++i) {
    put<float>(s, i == 5 ? std::numeric_limits<float>::infinity() : 1.0f * static_cast<float>(i));
  }
  write_bytes(dir / "inf.ply", s);
  expect_error([&] { read(dir / "inf.ply"); }, {"vertex 1 has a non-finite coordinate", "inf"});
}

TEST(MeshIoPly, FaceErrorsNameTheFace) {
  auto dir = test::scratch_dir();
  write_bytes(dir / "range.ply", kAsciiHead + kAsciiVertices + "3 0 1 2\n3 0 1 7\n");
  expect_error([&] { read(dir / "range.ply"); },
               {"face 1 (line 15) refers to vertex 7", "has 4 vertices"});
  write_bytes(dir / "neg.ply", kAsciiHead + kAsciiVertices + "3 0 -1 2\n3 0 1 2\n");
  expect_error([&] { read(dir / "neg.ply"); }, {"face 0 (line 14) refers to vertex -1"});
  write_bytes(dir / "two.ply", kAsciiHead + kAsciiVertices + "2 0 1\n3 0 1 2\n");
  expect_error([&] { read(dir / "two.ply"); }, {"face 0 (line 14) has 2 vertex indices"});
  write_bytes(dir / "word.ply", kAsciiHead + kAsciiVertices + "3 0 1 2\n3 0 x 2\n");
  expect_error([&] { read(dir / "word.ply"); }, {"face 1 (line 15)", "'x' is not an integer"});
  write_bytes(dir / "vword.ply", kAsciiHead + "0 0 0\n1 0 zero\n");
  expect_error([&] { read(dir / "vword.ply"); }, {"vertex 1 (line 11)", "'zero' is not a number"});

  std::string s =
      "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nelement face 1\n"
      "property list uchar uint vertex_indices\nend_header\n";
  for (int i = 0; i < 9; ++i)
    put<float>(s, static_cast<float>(i % 4), true);
  put<std::uint8_t>(s, 3);
  for (std::uint32_t v : {0u, 3u, 1u})
    put<std::uint32_t>(s, v, true);
  write_bytes(dir / "range_be.ply", s);
  expect_error([&] { read(dir / "range_be.ply"); },
               {"face 0 refers to vertex 3", "has 3 vertices"});
}

TEST(MeshIoPly, DegenerateFacesAreErrorsOrDropped) {
  auto dir = test::scratch_dir();
  write_bytes(dir / "deg.ply", kAsciiHead + kAsciiVertices + "3 0 1 2\n3 0 2 2\n");
  expect_error([&] { read(dir / "deg.ply"); }, {"face 1 is degenerate", "zero area"});
  write_bytes(dir / "fan.ply",
              "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\nproperty double y\n"
              "property double z\nelement face 1\nproperty list uchar int vertex_indices\n"
              "end_header\n0 0 0\n1 0 0\n2 0 0\n1 1 0\n4 0 3 1 2\n");
  expect_error([&] { read(dir / "fan.ply"); }, {"face 0 (fan triangle 1 of 2) is degenerate"});
  MeshReadOptions drop;
  drop.degenerate_faces = DegenerateFaces::kDrop;
  MeshReadReport report;
  TriangleMesh m = read_ply(dir / "deg.ply", drop, &report);
  EXPECT_EQ(m.triangles, (std::vector<Triangle>{{0, 1, 2}}));
  EXPECT_EQ(report.degenerate_triangles_dropped, 1u);
}

std::string binary_head(std::size_t vertices, std::size_t faces, const char* list = "uchar int") {
  return "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(vertices) +
         "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
         std::to_string(faces) + "\nproperty list " + list + " vertex_indices\nend_header\n";
}

void put_vertices(std::string& s, int n) {
  for (int i = 0; i < n; ++i) {
    put<float>(s, static_cast<float>(i % 2));
    put<float>(s, static_cast<float>(i / 2));
    put<float>(s, 0.0f);
  }
}

TEST(MeshIoPly, TruncatedBinaryNamesBytesAndElement) {
  auto dir = test::scratch_dir();
  std::string s = binary_head(3, 0);
  const std::size_t header = s.size();
  put_vertices(s, 3);
  s.resize(s.size() - 6);
  write_bytes(dir / "v.ply", s);
  expect_error([&] { read(dir / "v.ply"); },
               {"truncated", "3 \"vertex\" records of 12 bytes", "need 36 bytes",
                "file size " + std::to_string(header + 36),
                "the file has " + std::to_string(header + 30) + " bytes", "inside vertex 2"});

  s = binary_head(4, 2);
  put_vertices(s, 4);
  put<std::uint8_t>(s, 3);
  for (std::int32_t v : {0, 1, 2})
    put<std::int32_t>(s, v);
  put<std::uint8_t>(s, 3);
  put<std::int32_t>(s, 0);
  write_bytes(dir / "f.ply", s);
  expect_error([&] { read(dir / "f.ply"); },
               {"truncated", "inside face 1 of 2", "needs 12 more bytes",
                "the file has " + std::to_string(s.size()) + " bytes"});
}

TEST(MeshIoPly, BinaryDataAfterTheLastElement) {
  auto dir = test::scratch_dir();
  std::string s = binary_head(3, 0);
  put_vertices(s, 4);
  write_bytes(dir / "extra.ply", s);
  expect_error([&] { read(dir / "extra.ply"); },
               {"12 bytes after the last element", "counts do not match"});
}

TEST(MeshIoPly, CorruptCountsDoNotAllocateHugeBuffers) {
  auto dir = test::scratch_dir();
  std::string s = binary_head(4000000000u, 0);
  put_vertices(s, 3);
  write_bytes(dir / "huge.ply", s);
  expect_error([&] { read(dir / "huge.ply"); }, {"truncated", "4000000000"});

  s = binary_head(3, 1, "uint int");
  put_vertices(s, 3);
  put<std::uint32_t>(s, 0xffffffffu);
  for (std::int32_t v : {0, 1, 2})
    put<std::int32_t>(s, v);
  write_bytes(dir / "list.ply", s);
  expect_error([&] { read(dir / "list.ply"); }, {"truncated", "inside face 0 of 1"});

  write_bytes(dir / "huge_ascii.ply",
              "ply\nformat ascii 1.0\nelement vertex 3999999999\nproperty float x\n"
              "property float y\nproperty float z\nend_header\n0 0 0\n");
  expect_error([&] { read(dir / "huge_ascii.ply"); }, {"truncated", "3999999999"});
  write_bytes(dir / "wide.ply",
              "ply\nformat ascii 1.0\nelement vertex 999999999999\nproperty float x\n"
              "property float y\nproperty float z\nend_header\n0 0 0\n");
  expect_error([&] { read(dir / "wide.ply"); }, {"too many vertices (999999999999)"});
}

TEST(MeshIoPly, MalformedHeaders) {
  auto dir = test::scratch_dir();
  auto check = [&](const std::string& name, const std::string& text,
                   std::initializer_list<std::string_view> fragments) {
    write_bytes(dir / name, text);
    expect_error([&] { read(dir / name); }, fragments);
  };
  check("magic.ply", "plx\nformat ascii 1.0\nend_header\n", {"not a PLY file"});
  check("end.ply", "ply\nformat ascii 1.0\nelement vertex 0\n", {"no \"end_header\""});
  check("enc.ply", "ply\nformat binary_middle_endian 1.0\nend_header\n",
        {"header line 2", "binary_middle_endian"});
  check("ver.ply", "ply\nformat ascii 2.0\nend_header\n", {"header line 2", "version"});
  check("type.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float3 x\nend_header\n",
        {"header line 4", "unknown type 'float3'"});
  check("orphan.ply", "ply\nformat ascii 1.0\nproperty float x\nend_header\n",
        {"header line 3", "property before any element"});
  check("nox.ply",
        "ply\nformat ascii 1.0\nelement vertex 1\nproperty float y\nproperty float z\n"
        "end_header\n1 2\n",
        {"no \"x\" property"});
  check("novert.ply", "ply\nformat ascii 1.0\nelement point 1\nproperty float x\nend_header\n1\n",
        {"no \"vertex\" element"});
  check("noidx.ply",
        "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
        "property float z\nelement face 0\nproperty list uchar int corners\nend_header\n",
        {"no \"vertex_indices\""});
  check("noformat.ply", "ply\nelement vertex 0\nend_header\n", {"no \"format\""});
  check("empty.ply", "", {"empty file"});
}

}  // namespace
}  // namespace truecut::offline
