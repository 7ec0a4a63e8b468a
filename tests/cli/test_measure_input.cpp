// `truecut scan` and `truecut cmm` on hostile input (issue 23, the sweep's
// findings F1, F13, F19, F22, F25 and the output folder checked before the
// work): each case is refused, or reported as the failure it is, with a
// message that names the file and line, and nothing written.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "run_process.hpp"
#include "test_paths.hpp"

using namespace truecut::test;
namespace fs = std::filesystem;

namespace {

ProcessResult run_truecut(std::vector<std::string> args) {
  args.insert(args.begin(), cli_path().string());
  return run_process(args);
}

void write_text(const fs::path& f, const std::string& text) {
  std::ofstream(f, std::ios::binary) << text;
}

// An ASCII STL of the cube [0, a]³ (outward normals).
void write_cube(const fs::path& f, double a) {
  const double v[8][3] = {{0, 0, 0}, {a, 0, 0}, {a, a, 0}, {0, a, 0},
                          {0, 0, a}, {a, 0, a}, {a, a, a}, {0, a, a}};
  const int t[12][3] = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                        {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
  std::string s = "solid cube\n";
  for (const auto& f3 : t) {
    s += "facet normal 0 0 0\nouter loop\n";
    for (int c : f3)
      s += "vertex " + std::to_string(v[c][0]) + " " + std::to_string(v[c][1]) + " " +
           std::to_string(v[c][2]) + "\n";
    s += "endloop\nendfacet\n";
  }
  write_text(f, s + "endsolid cube\n");
}

// Points 0.05 mm outside the top (surface 1) and the +x face (surface 2)
// of the 10 mm cube; the +x face's at x_face.
std::string cube_points(const std::string& x_face = "10.05") {
  std::string s = "x,y,z,nx,ny,nz,surface\n";
  for (int i = 1; i < 5; ++i) {
    s += std::to_string(2 * i) + ",5,10.05,0,0,1,1\n";
    s += x_face + ",5," + std::to_string(2 * i) + ",1,0,0,2\n";
  }
  return s;
}

// The implant at a coarse mesh (a second or two).
fs::path make_part(const fs::path& dir) {
  const ProcessResult r =
      run_truecut({"part", "implant", "--mesh-edge", "2", "--stepover", "2", "--point-spacing", "2",
                   "--step-down", "4", "--out", (dir / "p").string()});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return dir / "p";
}

// A binary STL with every coordinate multiplied by k (a nominal in µm: 1000).
void write_scaled_stl(const fs::path& from, const fs::path& to, float k) {
  std::string stl = read_file(from);
  std::uint32_t n = 0;
  std::memcpy(&n, stl.data() + 80, 4);
  ASSERT_EQ(stl.size(), 84u + 50u * n);
  for (std::uint32_t f = 0; f < n; ++f)
    for (int c = 0; c < 3; ++c) {
      float xyz[3];
      char* at = stl.data() + 84 + 50 * f + 12 + 12 * c;
      std::memcpy(xyz, at, 12);
      for (float& x : xyz)
        x *= k;
      std::memcpy(at, xyz, 12);
    }
  write_text(to, stl);
}

}  // namespace

// F1: a probe point at x = 1e20 mm reached Embree, which asserted (SIGABRT,
// exit 134). It is refused at its line, with the range of the recording and
// machine readers.
TEST(MeasureInput, AProbeBeyondAnyMachineIsRefusedAtItsLine) {
  const fs::path dir = scratch_dir();
  write_cube(dir / "cube.stl", 10);
  write_text(dir / "p.csv", "x,y,z,nx,ny,nz,surface\n5,5,10,0,0,1,1\n1e20,0,5,1,0,0,1\n");
  const ProcessResult r =
      run_truecut({"cmm", (dir / "cube.stl").string(), "--points", (dir / "p.csv").string(),
                   "--out", (dir / "o.csv").string()});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("p.csv:3: x 1e+20 mm is outside ±1e+05 mm (no machine is larger than 100 m"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(dir / "o.csv"));
}

// F13: when no probe found the surface (a mesh in metres) cmm exited 0 with
// a table of 0.00, which reads as a perfect part. A measurement in which
// every probe failed has failed: exit 1, no table, no file. A surface no
// probe found among others that were measured shows "-", not 0.00.
TEST(MeasureInput, NoProbeFindingTheSurfaceIsAFailedMeasurement) {
  const fs::path dir = scratch_dir();
  write_cube(dir / "metres.stl", 0.01);
  write_text(dir / "p.csv", cube_points());
  ProcessResult r = run_truecut({"cmm", (dir / "metres.stl").string(), "--points",
                                 (dir / "p.csv").string(), "--out", (dir / "o.csv").string()});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("none of the 8 points found the surface of"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("nothing written"), std::string::npos) << r.err;
  EXPECT_EQ(r.out.find("0.00"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir / "o.csv"));

  // The +x face 3 mm off: its four probes find nothing within 1 mm.
  write_cube(dir / "cube.stl", 10);
  write_text(dir / "p2.csv", cube_points("13"));
  r = run_truecut({"cmm", (dir / "cube.stl").string(), "--points", (dir / "p2.csv").string(),
                   "--out", (dir / "o2.csv").string()});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  const std::size_t row = r.out.find("\n2 ");
  ASSERT_NE(row, std::string::npos) << r.out;
  const std::string line = r.out.substr(row + 1, r.out.find('\n', row + 1) - row - 1);
  EXPECT_EQ(line.substr(0, 24), "2              4       0") << line;
  EXPECT_EQ(line.find("0.00"), std::string::npos) << line;
  EXPECT_EQ(line.back(), '-') << line;
  EXPECT_TRUE(fs::exists(dir / "o2.csv"));
}

// F22: a nominal in µm (17 m across, inside the mesh readers' 1 km) asked
// for about 1e8 probes at the default spacing: 3.4 GB and still running at
// 60 s. The estimate from the surfaces' area is refused at once, naming
// the budget and the option that raises it.
TEST(MeasureInput, AProbeCountOverTheBudgetIsRefusedAtOnce) {
  const fs::path dir = scratch_dir();
  const fs::path p = make_part(dir);
  write_scaled_stl(p / "nominal.stl", dir / "um.stl", 1000.0f);
  const std::string um = (dir / "um.stl").string();
  ProcessResult r = run_truecut({"cmm", um, "--nominal", um, "--part", (p / "part.json").string(),
                                 "--out", (dir / "c.csv").string()});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--spacing 1 mm would probe about"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("more than --max-points 2000000"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "c.csv"));

  const std::string nominal = (p / "nominal.stl").string();
  r = run_truecut({"cmm", nominal, "--nominal", nominal, "--part", (p / "part.json").string(),
                   "--max-points", "10", "--out", (dir / "c.csv").string()});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("more than --max-points 10 "), std::string::npos) << r.err;
  r = run_truecut({"cmm", nominal, "--nominal", nominal, "--part", (p / "part.json").string(),
                   "--max-points", "100000", "--out", (dir / "c.csv").string()});
  EXPECT_EQ(r.exit_code, 0) << r.err;
}

// F19: --out and --mesh-out naming the same new file gave exit 0 and the
// scan mesh in place of the point cloud.
TEST(MeasureInput, ScanOutAndMeshOutNamingOneNewFileAreRefused) {
  const fs::path dir = scratch_dir();
  write_cube(dir / "cube.stl", 10);
  const ProcessResult r =
      run_truecut({"scan", (dir / "cube.stl").string(), "--out", (dir / "s.ply").string(),
                   "--mesh-out", (dir / "." / "s.ply").string()});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("name the same file"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "s.ply"));
}

// F25: the mesh and point readers said "cannot read the file size:
// Operation not supported" for /dev/zero and "read error" for a folder
// (and blocked on a FIFO); they give the common input check's message.
TEST(MeasureInput, MeshAndPointReadersRefuseWhatIsNotARegularFile) {
  const fs::path dir = scratch_dir();
  write_cube(dir / "cube.stl", 10);
  write_text(dir / "p.csv", cube_points());
  const std::string cube = (dir / "cube.stl").string(), out = (dir / "o.csv").string();
  struct Case {
    std::vector<std::string> args;
    std::string says;
  };
  std::vector<Case> cases = {
      {{"cmm", cube, "--points", dir.string(), "--out", out},
       dir.string() + ": is a folder, not a CMM point list"},
      {{"cmm", dir.string(), "--points", (dir / "p.csv").string(), "--out", out},
       dir.string() + ": is a folder, not a mesh or point cloud"},
      {{"scan", dir.string(), "--out", (dir / "s.ply").string()},
       dir.string() + ": is a folder, not a mesh or point cloud"},
  };
  if (fs::exists("/dev/zero")) {
    const std::string device = "/dev/zero: is not a regular file (a device, pipe or socket";
    cases.push_back({{"cmm", cube, "--points", "/dev/zero", "--out", out}, device});
    cases.push_back(
        {{"cmm", "/dev/zero", "--points", (dir / "p.csv").string(), "--out", out}, device});
    cases.push_back({{"scan", "/dev/zero", "--out", (dir / "s.ply").string()}, device});
  }
  for (const Case& c : cases) {
    const ProcessResult r = run_truecut(c.args);
    EXPECT_EQ(r.exit_code, 2) << c.args[0] << " " << c.args[1] << ": " << r.err;
    EXPECT_NE(r.err.find(c.says), std::string::npos) << r.err;
  }
  EXPECT_FALSE(fs::exists(out));
}

// An output that cannot be written (under /proc) was found only after all
// the work; it is refused before any, and nothing is left.
TEST(MeasureInput, AnOutputThatCannotBeWrittenIsRefusedBeforeTheWork) {
  if (!fs::is_directory("/proc/self")) GTEST_SKIP() << "no /proc on this system";
  const fs::path dir = scratch_dir();
  write_cube(dir / "cube.stl", 10);
  write_text(dir / "p.csv", cube_points());
  const std::string cube = (dir / "cube.stl").string();
  for (const auto& args : std::vector<std::vector<std::string>>{
           {"scan", cube, "--out", "/proc/truecut-scan.ply"},
           {"cmm", cube, "--points", (dir / "p.csv").string(), "--out", "/proc/truecut-cmm.csv"},
       }) {
    const ProcessResult r = run_truecut(args);
    EXPECT_EQ(r.exit_code, 2) << args[0] << ": " << r.err;
    EXPECT_NE(r.err.find("cannot write in /proc"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("scan: pose"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("cmm: probing"), std::string::npos) << r.err;
  }
  const ProcessResult r =
      run_truecut({"scan", cube, "--out", (dir / "missing" / "s.ply").string()});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("does not exist"), std::string::npos) << r.err;
}

// F7 for every reader of part.json: `cmm --part` with `units` "inch" or a
// tool of radius 0 exited 0 (only `run` and the cutting model checked
// them); `field --part` read them too. Refused at the key, exit 2.
TEST(MeasureInput, APartFileWithoutPhysicalSenseIsRefusedByEveryCommand) {
  const fs::path dir = scratch_dir();
  const fs::path p = make_part(dir);
  const std::string part = read_file(p / "part.json");
  struct Case {
    const char *from, *to, *says;
  };
  for (const Case& c : {Case{"\"units\": \"mm\"", "\"units\": \"inch\"",
                             "key 'units': 'inch': part.json lengths are millimetres"},
                        Case{"\"radius_mm\": 1.0", "\"radius_mm\": 0.0",
                             "key 'tools[0].radius_mm': 0 mm must be > 0 and at most 500 mm"}}) {
    std::string text = part;
    const auto at = text.find(c.from);
    ASSERT_NE(at, std::string::npos) << c.from;
    text.replace(at, std::strlen(c.from), c.to);
    const fs::path bad = dir / "bad_part.json";
    std::ofstream(bad, std::ios::binary) << text;
    const std::string nominal = (p / "nominal.stl").string();
    const ProcessResult cmm = run_truecut({"cmm", nominal, "--nominal", nominal, "--part",
                                           bad.string(), "--out", (dir / "c.csv").string()});
    EXPECT_EQ(cmm.exit_code, 2) << cmm.err;
    EXPECT_NE(cmm.err.find(bad.string() + ": " + c.says), std::string::npos) << cmm.err;
    EXPECT_FALSE(fs::exists(dir / "c.csv"));
    const ProcessResult field = run_truecut(
        {"field", nominal, nominal, "--program", (p / "program.ngc").string(), "--tools",
         (p / "tools.tbl").string(), "--part", bad.string(), "--out", (dir / "f").string()});
    EXPECT_EQ(field.exit_code, 2) << field.err;
    EXPECT_NE(field.err.find(c.says), std::string::npos) << field.err;
    EXPECT_FALSE(fs::exists(dir / "f" / "field.tcf"));
  }
}
