#include "mesh_io_test_util.hpp"
#include "test_paths.hpp"

#include <cmath>
#include <limits>

namespace truecut::offline {
namespace {

using test_util::expect_error;
using test_util::put;
using test_util::write_bytes;
using Facet = std::array<std::array<float, 3>, 3>;

// A binary STL made byte by byte; `declared` overrides the facet count.
std::string binary_stl(std::string_view header, const std::vector<Facet>& facets,
                       std::int64_t declared = -1) {
  std::string s(header.substr(0, 80));
  s.resize(80, ' ');
  put<std::uint32_t>(s, declared < 0 ? static_cast<std::uint32_t>(facets.size())
                                     : static_cast<std::uint32_t>(declared));
  for (const Facet& f : facets) {
    for (int k = 0; k < 3; ++k)
      put<float>(s, 0.0f);
    for (const auto& corner : f) {
      for (float v : corner)
        put<float>(s, v);
    }
    put<std::uint16_t>(s, 0);
  }
  return s;
}

const std::vector<Facet> kTetra = {
    Facet{{{0, 0, 0}, {0, 1, 0}, {1, 0, 0}}},
    Facet{{{0, 0, 0}, {1, 0, 0}, {0, 0, 1}}},
    Facet{{{0, 0, 0}, {0, 0, 1}, {0, 1, 0}}},
    Facet{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}},
};

TEST(MeshIoStl, BinaryWhoseHeaderStartsWithSolidIsReadAsBinary) {
  auto dir = test::scratch_dir();
  write_bytes(dir / "part.stl", binary_stl("solid part exported by a CAD system", kTetra));
  MeshReadReport report;
  TriangleMesh m = read_stl(dir / "part.stl", {}, &report);
  EXPECT_EQ(report.encoding, "binary");
  ASSERT_EQ(m.vertices_mm.size(), 4u);  // welded from 12 corners
  ASSERT_EQ(m.triangles.size(), 4u);
  EXPECT_EQ(report.stl_corners_welded, 8u);
  EXPECT_EQ(m.vertices_mm[0], Eigen::Vector3d(0, 0, 0));
  EXPECT_EQ(m.vertices_mm[1], Eigen::Vector3d(0, 1, 0));
  EXPECT_EQ(m.vertices_mm[2], Eigen::Vector3d(1, 0, 0));
  EXPECT_EQ(m.vertices_mm[3], Eigen::Vector3d(0, 0, 1));
  EXPECT_EQ(m.triangles[3], (Triangle{2, 1, 3}));
  EXPECT_FALSE(m.has_normals());
  ASSERT_EQ(report.comments.size(), 1u);
  EXPECT_EQ(report.comments[0], "solid part exported by a CAD system");
}

TEST(MeshIoStl, WeldingCanBeSwitchedOffAndTreatsSignedZerosAsOne) {
  auto dir = test::scratch_dir();
  std::vector<Facet> f = {Facet{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}},
                          Facet{{{1, 0, 0}, {1, 1, 0}, {-0.0f, 1, -0.0f}}}};
  write_bytes(dir / "two.stl", binary_stl("two facets", f));
  TriangleMesh welded = read_stl(dir / "two.stl");
  EXPECT_EQ(welded.vertices_mm.size(), 4u);
  EXPECT_EQ(welded.triangles[1], (Triangle{1, 3, 2}));
  MeshReadOptions no_weld;
  no_weld.weld_stl_vertices = false;
  TriangleMesh plain = read_stl(dir / "two.stl", no_weld);
  EXPECT_EQ(plain.vertices_mm.size(), 6u);
  EXPECT_EQ(plain.triangles[1], (Triangle{3, 4, 5}));
}

TEST(MeshIoStl, HandWrittenAscii) {
  auto dir = test::scratch_dir();
  write_bytes(dir / "tetra.stl",
              "solid tetra\r\n"
              "  facet normal 0 0 -1\r\n    outer loop\r\n"
              "      vertex 0 0 0\r\n      vertex 0 1 0\r\n      vertex 1 0 0\r\n"
              "    endloop\r\n  endfacet\r\n"
              "  FACET NORMAL 0 -1 0\r\n    OUTER LOOP\r\n"
              "      VERTEX 0.0 0.0 0.0\r\n      VERTEX +1e0 0 0\r\n      VERTEX 0 0 1.5\r\n"
              "    ENDLOOP\r\n  ENDFACET\r\n"
              "endsolid tetra\r\n"
              "solid second\n"
              "facet normal 0 0 0\nouter loop\nvertex 0 0 0\nvertex 0 0 1.5\nvertex 0 1 0\n"
              "endloop\nendfacet\nendsolid second\n");
  MeshReadReport report;
  TriangleMesh m = read_stl(dir / "tetra.stl", {}, &report);
  EXPECT_EQ(report.encoding, "ascii");
  ASSERT_EQ(m.triangles.size(), 3u);
  ASSERT_EQ(m.vertices_mm.size(), 4u);
  EXPECT_EQ(m.vertices_mm[3], Eigen::Vector3d(0, 0, 1.5));
  EXPECT_EQ(m.triangles[1], (Triangle{0, 2, 3}));
  EXPECT_EQ(m.triangles[2], (Triangle{0, 3, 1}));
  ASSERT_EQ(report.comments.size(), 2u);
  EXPECT_EQ(report.comments[1], "second");
}

TEST(MeshIoStl, RoundTripBinaryAndAscii) {
  auto dir = test::scratch_dir();
  TriangleMesh mesh = test_util::grid_mesh(40, 30);
  const TriangleMesh expected = test_util::by_first_use(mesh);
  write_stl(dir / "b.stl", mesh, StlEncoding::kBinary, "nominal");
  write_stl(dir / "a.stl", mesh, StlEncoding::kAscii, "nominal");
  MeshReadReport rb, ra;
  test_util::expect_same(read_stl(dir / "b.stl", {}, &rb), expected);
  test_util::expect_same(read_stl(dir / "a.stl", {}, &ra), expected);
  EXPECT_EQ(rb.encoding, "binary");
  EXPECT_EQ(ra.encoding, "ascii");
  EXPECT_EQ(std::filesystem::file_size(dir / "b.stl"), 84 + 50 * mesh.triangles.size());
}

TEST(MeshIoStl, AsciiRoundTripKeepsFullDoublePrecision) {
  auto dir = test::scratch_dir();
  TriangleMesh mesh;
  mesh.vertices_mm = {
      {0.1, 1.0 / 3.0, -2.718281828459045}, {10.000000000000002, 0, 1e-300}, {0, 123456.789, 0.3}};
  mesh.triangles = {{0, 1, 2}};
  write_stl(dir / "a.stl", mesh, StlEncoding::kAscii);
  test_util::expect_same(read_stl(dir / "a.stl"), mesh);
}

TEST(MeshIoStl, TruncatedBinaryNamesBytesAndFacet) {
  auto dir = test::scratch_dir();
  std::string bytes = binary_stl("solid but binary", kTetra);
  bytes.resize(84 + 2 * 50 + 20);  // inside facet 2
  write_bytes(dir / "cut.stl", bytes);
  expect_error([&] { read_stl(dir / "cut.stl"); },
               {"cut.stl", "truncated", "4 facets", "284 bytes", "204 bytes", "facet 2"});
}

TEST(MeshIoStl, ShortBinaryPreamble) {
  auto dir = test::scratch_dir();
  write_bytes(dir / "short.stl", std::string("\x01\x02\x03", 3));
  expect_error([&] { read_stl(dir / "short.stl"); }, {"truncated", "84", "has 3"});
}

TEST(MeshIoStl, FacetCountThatDoesNotMatchTheData) {
  auto dir = test::scratch_dir();
  write_bytes(dir / "count.stl", binary_stl("x", kTetra, 3));
  expect_error([&] { read_stl(dir / "count.stl"); },
               {"does not match", "3 facets", "234 bytes", "284 bytes"});
}

TEST(MeshIoStl, NonFiniteCoordinatesNameTheFacet) {
  auto dir = test::scratch_dir();
  auto f = kTetra;
  f[2][1][0] = std::numeric_limits<float>::quiet_NaN();
  write_bytes(dir / "nan.stl", binary_stl("x", f));
  expect_error([&] { read_stl(dir / "nan.stl"); }, {"facet 2 corner 1", "non-finite", "nan"});
  f[2][1][0] = std::numeric_limits<float>::infinity();
  write_bytes(dir / "inf.stl", binary_stl("x", f));
  expect_error([&] { read_stl(dir / "inf.stl"); }, {"facet 2 corner 1", "inf"});

  write_bytes(dir / "nan_ascii.stl",
              "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
              "vertex 0 1 0\nendloop\nendfacet\nfacet normal 0 0 1\nouter loop\n"
              "vertex 0 0 0\nvertex NaN 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid s\n");
  expect_error([&] { read_stl(dir / "nan_ascii.stl"); }, {"facet 1 corner 1", "line 12"});
}

TEST(MeshIoStl, DegenerateFacetsAreErrorsOrDropped) {
  auto dir = test::scratch_dir();
  auto f = kTetra;
  f.push_back(Facet{{{0, 0, 0}, {1, 1, 1}, {2, 2, 2}}});  // collinear
  f.push_back(Facet{{{1, 0, 0}, {1, 0, 0}, {0, 1, 0}}});  // repeated corner
  write_bytes(dir / "deg.stl", binary_stl("x", f));
  expect_error([&] { read_stl(dir / "deg.stl"); }, {"facet 4 is degenerate", "zero area"});
  MeshReadOptions drop;
  drop.degenerate_faces = DegenerateFaces::kDrop;
  MeshReadReport report;
  TriangleMesh m = read_stl(dir / "deg.stl", drop, &report);
  EXPECT_EQ(m.triangles.size(), 4u);
  EXPECT_EQ(report.degenerate_triangles_dropped, 2u);
  EXPECT_EQ(report.faces_in_file, 6u);
}

TEST(MeshIoStl, MalformedAscii) {
  auto dir = test::scratch_dir();
  const std::string head = "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n";
  write_bytes(dir / "cut.stl", head + "vertex 1 0 0\n");
  expect_error([&] { read_stl(dir / "cut.stl"); }, {"truncated", "inside facet 0", "line 5"});
  write_bytes(dir / "noend.stl", head + "vertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n");
  expect_error([&] { read_stl(dir / "noend.stl"); }, {"truncated", "endsolid"});
  write_bytes(dir / "four.stl",
              head + "vertex 1 0 0\nvertex 0 1 0\nvertex 1 1 0\nendloop\nendfacet\nendsolid\n");
  expect_error([&] { read_stl(dir / "four.stl"); }, {"line 7", "facet 0 has more than 3"});
  write_bytes(dir / "two.stl", head + "vertex 1 0 0\nendloop\nendfacet\nendsolid\n");
  expect_error([&] { read_stl(dir / "two.stl"); }, {"line 6", "facet 0 has 2 vertices"});
  write_bytes(dir / "word.stl", head + "vertex 1 zero 0\n");
  expect_error([&] { read_stl(dir / "word.stl"); }, {"line 5", "'zero' is not a number"});
  write_bytes(dir / "key.stl", "solid s\nfacet normal 0 0 1\nouter lop\n");
  expect_error([&] { read_stl(dir / "key.stl"); }, {"line 3", "outer loop"});
}

TEST(MeshIoStl, EmptyFiles) {
  auto dir = test::scratch_dir();
  write_bytes(dir / "empty.stl", "");
  expect_error([&] { read_stl(dir / "empty.stl"); }, {"empty.stl", "empty file"});
  write_bytes(dir / "blank.stl", "  \n\n");
  expect_error([&] { read_stl(dir / "blank.stl"); }, {"empty file"});
  expect_error([&] { read_stl(dir / "missing.stl"); }, {"missing.stl", "cannot open"});
}

TEST(MeshIoStl, BinaryHeaderMustNotStartWithSolidWhenWriting) {
  auto dir = test::scratch_dir();
  expect_error(
      [&] {
        write_stl(dir / "x.stl", test_util::grid_mesh(3, 3), StlEncoding::kBinary, "solid x");
      },
      {"solid"});
  EXPECT_EQ(test_util::files_in(dir), 0u);
}

TEST(MeshIoStl, AMistypedAsciiHeaderIsNamedAsSuch) {
  // Issue 23: "solud" was read as binary and reported 807,434,341 facets.
  auto dir = test::scratch_dir();
  const std::string body =
      " facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n"
      "   vertex 0 1 0\n  endloop\n endfacet\nendsolid x\n";
  write_bytes(dir / "typo.stl", "solud x\n" + body);
  expect_error([&] { read_stl(dir / "typo.stl"); },
               {"typo.stl", "looks like an ASCII STL", "does not start with 'solid'",
                "first line is 'solud x'"});
  write_bytes(dir / "notes.stl", "these are my notes about the part\nnothing else\n");
  expect_error([&] { read_stl(dir / "notes.stl"); },
               {"notes.stl", "is text, not an STL", "'these are my notes about the part'"});
}

TEST(MeshIoStl, ACoordinateBeyondAnyPartIsRefusedNotCalledDegenerate) {
  // Issue 23: a corner at 1e39 mm was reported as a degenerate facet.
  auto dir = test::scratch_dir();
  write_bytes(dir / "big.stl",
              "solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n"
              "   vertex 1e39 0 0\n   vertex 0 1 0\n  endloop\n endfacet\nendsolid x\n");
  expect_error([&] { read_stl(dir / "big.stl"); },
               {"big.stl", "facet 0 corner 1 (1e+39, 0, 0) is outside", "check the unit"});
  // 1 km is still a part (a bridge girder).
  write_bytes(dir / "large.stl",
              "solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n"
              "   vertex 999999 0 0\n   vertex 0 999999 0\n  endloop\n endfacet\nendsolid x\n");
  EXPECT_EQ(1u, read_stl(dir / "large.stl").triangles.size());
}

}  // namespace
}  // namespace truecut::offline
