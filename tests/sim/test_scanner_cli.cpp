// `truecut scan`: a scan of a written mesh, byte-identical per seed, and
// input errors that exit 2 without writing anything.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <fstream>

#include "run_process.hpp"
#include "test_paths.hpp"
#include "test_scanner_meshes.hpp"
#include "truecut/offline/mesh_io.hpp"

using namespace truecut::test;

namespace {

std::filesystem::path write_box(const std::filesystem::path& dir) {
  const auto file = dir / "box.stl";
  truecut::offline::write_mesh(file, box_mesh({-10, -8, 0}, {10, 8, 12}));
  return file;
}

ProcessResult scan_cli(std::vector<std::string> args) {
  args.insert(args.begin(), {cli_path().string(), "scan"});
  return run_process(args);
}

}  // namespace

TEST(ScanCli, WritesACloudAndAMeshRepeatably) {
  const auto dir = scratch_dir();
  const auto box = write_box(dir);
  for (const char* name : {"a", "b"}) {
    auto r =
        scan_cli({box.string(), "--out", (dir / (std::string(name) + ".ply")).string(), "--density",
                  "4", "--mesh-out", (dir / (std::string(name) + "_mesh.ply")).string(),
                  "--registration-error-mm", "0.05", "--registration-error-deg", "0.1"});
    ASSERT_EQ(0, r.exit_code) << r.err;
    EXPECT_NE(std::string::npos, r.out.find("5 poses")) << r.out;
    EXPECT_EQ(std::string::npos, r.err.find("scan: pose")) << r.err;  // progress: a terminal's
  }
  EXPECT_EQ(read_file(dir / "a.ply"), read_file(dir / "b.ply"));
  EXPECT_EQ(read_file(dir / "a_mesh.ply"), read_file(dir / "b_mesh.ply"));
  const auto cloud = truecut::offline::read_point_cloud(dir / "a.ply");
  EXPECT_TRUE(cloud.has_normals());
  // Five faces of 320, 240, 240, 192, 192 mm² at 4 pt/mm².
  EXPECT_NEAR(4.0 * (320 + 2 * 240 + 2 * 192), static_cast<double>(cloud.points_mm.size()),
              0.1 * 4.0 * (320 + 2 * 240 + 2 * 192));
  const auto mesh = truecut::offline::read_mesh(dir / "a_mesh.ply");
  EXPECT_GT(mesh.triangles.size(), cloud.points_mm.size());

  auto other = scan_cli({box.string(), "--out", (dir / "c.xyz").string(), "--density", "4",
                         "--seed", "2", "--mode", "laser", "--sigma-um", "50"});
  ASSERT_EQ(0, other.exit_code) << other.err;
  EXPECT_FALSE(truecut::offline::read_point_cloud(dir / "c.xyz").points_mm.empty());
}

TEST(ScanCli, BadInputExitsTwoAndWritesNothing) {
  const auto dir = scratch_dir();
  const auto box = write_box(dir);
  const auto out = dir / "out.ply";
  struct Case {
    std::vector<std::string> args;
    std::string message;
  };
  std::ofstream(dir / "garbage.stl") << "solid x\nthis is not an stl\n";
  const std::vector<Case> cases = {
      {{box.string(), "--out", out.string(), "--sigma-um", "4"}, "--sigma-um 4 is outside"},
      {{box.string(), "--out", out.string(), "--sigma-um", "51"}, "--sigma-um 51 is outside"},
      {{box.string(), "--out", out.string(), "--mode", "sonar"}, "--mode 'sonar'"},
      {{box.string(), "--out", (dir / "out.obj").string()}, "must be .ply, .xyz"},
      {{box.string(), "--out", out.string(), "--mesh-out", (dir / "m.xyz").string()},
       "must be .ply or .stl"},
      {{(dir / "missing.stl").string(), "--out", out.string()}, "missing.stl"},
      {{(dir / "garbage.stl").string(), "--out", out.string()}, "garbage.stl"},
      {{box.string()}, "--out FILE is required"},
      {{box.string(), "--out", out.string(), "--registration-error-deg", "20"},
       "--registration-error-deg 20 is outside"},
  };
  for (const Case& c : cases) {
    const auto r = scan_cli(c.args);
    EXPECT_EQ(2, r.exit_code) << c.message << "\n" << r.err;
    EXPECT_NE(std::string::npos, r.err.find(c.message)) << r.err;
  }
  for (const auto& e : std::filesystem::directory_iterator(dir))
    EXPECT_TRUE(e.path().filename() == "box.stl" || e.path().filename() == "garbage.stl")
        << e.path();
}

TEST(ScanCli, NeverReplacesAFifo) {
  const auto dir = scratch_dir();
  const auto box = write_box(dir);
  const auto fifo = dir / "fifo.ply";
  ASSERT_EQ(0, ::mkfifo(fifo.c_str(), 0600));
  const auto r = scan_cli({box.string(), "--out", fifo.string(), "--density", "1"});
  EXPECT_EQ(2, r.exit_code);
  EXPECT_NE(std::string::npos, r.err.find("not a regular file")) << r.err;
  EXPECT_TRUE(std::filesystem::is_fifo(fifo));
}
