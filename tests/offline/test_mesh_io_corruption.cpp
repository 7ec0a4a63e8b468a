// Every truncation and many byte flips of valid files: a reader must either
// return a mesh or throw MeshIoError — never crash, hang or throw anything
// else (such as bad_alloc from a corrupt count).
#include "mesh_io_test_util.hpp"
#include "test_paths.hpp"

#include <random>

namespace truecut::offline {
namespace {

struct Outcome {
  std::size_t read = 0, refused = 0;
};

void read_all_variants(const std::filesystem::path& dir, const std::string& name,
                       const std::string& bytes, Outcome& out) {
  const auto file = dir / name;
  auto attempt = [&](const std::string& content, const std::string& what) {
    // A fresh file each time: ext4 flushes a file truncated and rewritten.
    std::filesystem::remove(file);
    test_util::write_bytes(file, content);
    try {
      read_mesh(file);
      ++out.read;
    } catch (const MeshIoError&) {
      ++out.refused;
    } catch (const std::exception& e) {
      ADD_FAILURE() << name << ", " << what << ": " << typeid(e).name() << ": " << e.what();
    }
  };
  for (std::size_t n = 0; n < bytes.size(); ++n) {
    attempt(bytes.substr(0, n), "truncated to " + std::to_string(n));
  }
  std::mt19937 rng(7);
  for (int i = 0; i < 400; ++i) {
    std::string s = bytes;
    const std::size_t at = rng() % s.size();
    s[at] = static_cast<char>(rng() & 0xff);
    attempt(s, "byte " + std::to_string(at) + " changed");
  }
}

TEST(MeshIoCorruption, OnlyMeshIoErrorsEscape) {
  auto dir = test::scratch_dir();
  const TriangleMesh mesh = test_util::grid_mesh(3, 3, true);
  TriangleMesh bare = mesh;
  bare.normals.clear();
  write_stl(dir / "ref.stl", bare);
  write_stl(dir / "ref_ascii.stl", bare, StlEncoding::kAscii);
  write_ply(dir / "ref_le.ply", mesh);
  write_ply(dir / "ref_be.ply", mesh, PlyEncoding::kBinaryBigEndian);
  write_ply(dir / "ref_ascii.ply", mesh, PlyEncoding::kAscii);
  write_point_text(dir / "ref.csv", PointCloud{mesh.vertices_mm, mesh.normals}, {',', true});
  Outcome out;
  for (const char* ref :
       {"ref.stl", "ref_ascii.stl", "ref_le.ply", "ref_be.ply", "ref_ascii.ply", "ref.csv"}) {
    const std::string bytes = test::read_file(dir / ref);
    read_all_variants(dir, std::string("v_") + ref, bytes, out);
  }
  std::printf("corrupted variants: %zu read, %zu refused with MeshIoError\n", out.read,
              out.refused);
  EXPECT_GT(out.refused, out.read);
}

}  // namespace
}  // namespace truecut::offline
