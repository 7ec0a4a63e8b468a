// `truecut run MACHINE PROGRAM --scan FILE --cmm FILE`: the machined part
// scanned and probed after the run; bad options are exit 2 with nothing
// written.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "face_job.hpp"
#include "run_process.hpp"
#include "test_paths.hpp"

namespace {

namespace fs = std::filesystem;
using namespace truecut::test;

ProcessResult truecut(std::vector<std::string> args) {
  args.insert(args.begin(), cli_path().string());
  return run_process(args);
}

// A coarse implant and its face program (face_job.hpp).
fs::path tiny_job(const fs::path& dir) {
  const fs::path part = dir / "part";
  const ProcessResult r = truecut(coarse_implant_part_args(part));
  EXPECT_EQ(0, r.exit_code) << r.err;
  std::ofstream(part / "face.ngc") << kFaceProgram;
  return part;
}

std::vector<std::string> run_args(const fs::path& part, const fs::path& out) {
  return {"run",
          (part / "machine_ideal.json").string(),
          (part / "face.ngc").string(),
          "--out",
          out.string(),
          "--dexel-spacing",
          "0.2"};
}

std::vector<std::string> with(std::vector<std::string> args, std::vector<std::string> more) {
  args.insert(args.end(), more.begin(), more.end());
  return args;
}

// Points of a binary little-endian PLY point cloud (x y z [nx ny nz] doubles).
std::vector<double> ply_points(const fs::path& file, std::size_t* doubles_per_vertex) {
  const std::string bytes = read_file(file);
  const std::size_t end = bytes.find("end_header\n");
  EXPECT_NE(std::string::npos, end);
  std::istringstream header(bytes.substr(0, end));
  std::string line;
  std::size_t vertices = 0, properties = 0;
  bool binary = false;
  while (std::getline(header, line)) {
    if (line == "format binary_little_endian 1.0") binary = true;
    if (line.rfind("element vertex ", 0) == 0) vertices = std::stoul(line.substr(15));
    if (line.rfind("property double ", 0) == 0) ++properties;
    EXPECT_EQ(std::string::npos, line.find("element face")) << "a point cloud";
  }
  EXPECT_TRUE(binary);
  const std::size_t data = end + std::strlen("end_header\n");
  EXPECT_EQ(bytes.size(), data + vertices * properties * sizeof(double));
  std::vector<double> v(vertices * properties);
  if (bytes.size() >= data + v.size() * sizeof(double))
    std::memcpy(v.data(), bytes.data() + data, v.size() * sizeof(double));
  *doubles_per_vertex = properties;
  return v;
}

TEST(RunMeasure, ScansAndProbesTheMachinedPart) {
  const fs::path dir = scratch_dir();
  const fs::path part = tiny_job(dir);
  const fs::path out = dir / "run";
  const ProcessResult r =
      truecut(with(run_args(part, out), {"--scan", "scan.ply", "--scan-sigma-um", "10",
                                         "--scan-seed", "3", "--cmm", "cmm.csv", "--cmm-surfaces",
                                         "1,5", "--cmm-spacing", "0.5", "--cmm-sigma-um", "0"}));
  ASSERT_EQ(0, r.exit_code) << r.err;
  EXPECT_NE(std::string::npos, r.out.find("scan.ply")) << r.out;
  EXPECT_NE(std::string::npos, r.out.find("cmm.csv")) << r.out;
  for (const char* f : {"machined.stl", "trace.csv", "scan.ply", "cmm.csv"})
    EXPECT_TRUE(fs::is_regular_file(out / f)) << f;
  EXPECT_FALSE(fs::exists(out / "scan.ply.tmp"));
  EXPECT_FALSE(fs::exists(out / "cmm.csv.tmp"));

  // The scan: a point cloud on the part (base 12 x 12 x 5, shaft to z 17.3).
  std::size_t stride = 0;
  const std::vector<double> cloud = ply_points(out / "scan.ply", &stride);
  ASSERT_EQ(6u, stride) << "points with normals";
  const std::size_t points = cloud.size() / stride;
  EXPECT_GT(points, 1000u);
  for (std::size_t i = 0; i < points; ++i) {
    const double x = cloud[i * stride], y = cloud[i * stride + 1], z = cloud[i * stride + 2];
    ASSERT_TRUE(std::abs(x) <= 6.1 && std::abs(y) <= 6.1 && z >= -5.1 && z <= 17.4)
        << "point " << i << " at " << x << " " << y << " " << z;
  }
  EXPECT_NE(std::string::npos, r.out.find(std::to_string(points) + " points")) << r.out;

  // The CMM: the faced top (surface 5) on size, the untouched side (1) 0.3 mm proud.
  std::istringstream csv(read_file(out / "cmm.csv"));
  std::string line;
  std::getline(csv, line);
  ASSERT_EQ("x,y,z,nx,ny,nz,surface,deviation_mm,valid", line);
  std::map<int, std::vector<double>> deviations;
  while (std::getline(csv, line)) {
    std::vector<std::string> cells;
    std::stringstream row(line);
    for (std::string c; std::getline(row, c, ',');)
      cells.push_back(c);
    ASSERT_EQ(9u, cells.size()) << line;
    if (cells[8] == "1") deviations[std::stoi(cells[6])].push_back(std::stod(cells[7]));
  }
  ASSERT_EQ(2u, deviations.size());
  for (const auto& [surface, d] : deviations) {
    ASSERT_GT(d.size(), 5u) << surface;
    double mean = 0;
    for (double v : d)
      mean += v / static_cast<double>(d.size());
    if (surface == 5)
      EXPECT_NEAR(0.0, mean, 0.02) << "faced top";
    else
      EXPECT_NEAR(0.3, mean, 0.02) << "side with its stock";
  }

  // The same request again gives the same files (seeded noise).
  const std::string scan_bytes = read_file(out / "scan.ply"),
                    cmm_bytes = read_file(out / "cmm.csv");
  const fs::path again = dir / "again";
  ASSERT_EQ(0, truecut(with(run_args(part, again),
                            {"--scan", "scan.ply", "--scan-sigma-um", "10", "--scan-seed", "3",
                             "--cmm", "cmm.csv", "--cmm-surfaces", "1,5", "--cmm-spacing", "0.5",
                             "--cmm-sigma-um", "0"}))
                   .exit_code);
  EXPECT_EQ(scan_bytes, read_file(again / "scan.ply"));
  EXPECT_EQ(cmm_bytes, read_file(again / "cmm.csv"));
}

TEST(RunMeasure, BadOptionsAreExitTwoWithNothingWritten) {
  const fs::path dir = scratch_dir();
  const fs::path part = tiny_job(dir);
  const fs::path out = dir / "run";
  struct Case {
    std::vector<std::string> extra;
    std::string message;
  };
  const std::vector<Case> cases = {
      {{"--scan", "scan.ply", "--scan-sigma-um", "500"}, "--scan-sigma-um 500 is outside"},
      {{"--scan-seed", "3"}, "--scan-seed needs --scan"},
      {{"--cmm-spacing", "1"}, "--cmm-spacing needs --cmm"},
      {{"--scan", "scan.stl"}, "--scan scan.stl: the point cloud must be .ply, .xyz, .txt or .csv"},
      {{"--scan", "scan.ply", "--scan-mode", "sonar"},
       "--scan-mode 'sonar': expected fringe or laser"},
      {{"--cmm", "cmm.csv", "--cmm-surfaces", "5,99"}, "key 'surfaces' has no surface 99"},
      {{"--cmm", "cmm.csv", "--cmm-surfaces", "5,x"}, "'x' is not a surface id"},
      {{"--cmm", "trace.csv"}, "--cmm trace.csv: the run writes trace.csv itself"},
      {{"--cmm", "/dev/null"}, "--cmm /dev/null: outside the output folder"},
      {{"--cmm", "../outside.csv"}, "--cmm ../outside.csv: outside the output folder"},
      {{"--scan", (dir / "abs.xyz").string()},
       "--scan " + (dir / "abs.xyz").string() + ": outside the output folder"},
      {{"--scan", "m.csv", "--cmm", "m.csv"}, "--scan and --cmm name the same file"},
  };
  for (const Case& c : cases) {
    const ProcessResult r = truecut(with(run_args(part, out), c.extra));
    EXPECT_EQ(2, r.exit_code) << c.message;
    EXPECT_NE(std::string::npos, r.err.find(c.message)) << r.err;
    EXPECT_FALSE(fs::exists(out)) << c.message << ": nothing written";
  }
  EXPECT_TRUE(fs::is_character_file("/dev/null"));
  EXPECT_FALSE(fs::exists(dir / "outside.csv"));
  EXPECT_FALSE(fs::exists(dir / "abs.xyz"));
}

// Issue 23: `--out PART_DIR --cmm tools.tbl` replaced the tool table the run
// had read with the CMM's CSV, exit 0.
TEST(RunMeasure, AMeasurementOverAnInputIsRefusedAndTheInputKept) {
  const fs::path dir = scratch_dir();
  const fs::path part = tiny_job(dir);
  const std::string tools = read_file(part / "tools.tbl");
  const ProcessResult r = truecut(with(run_args(part, part), {"--cmm", "tools.tbl"}));
  EXPECT_EQ(2, r.exit_code) << r.err;
  EXPECT_NE(std::string::npos, r.err.find("--cmm tools.tbl is the input ")) << r.err;
  EXPECT_EQ(tools, read_file(part / "tools.tbl"));
  EXPECT_FALSE(fs::exists(part / "trace.csv"));
}

// Issue 23: a CMM run in which no probe found the surface wrote a cmm.csv
// of invalid rows and exited 0, where `truecut cmm` fails: the untouched
// side stands 0.3 mm proud, beyond a search of 0.1 mm.
TEST(RunMeasure, ACmmRunInWhichNoProbeFindsTheSurfaceFails) {
  const fs::path dir = scratch_dir();
  const fs::path part = tiny_job(dir);
  const fs::path out = dir / "run";
  const ProcessResult r =
      truecut(with(run_args(part, out), {"--cmm", "cmm.csv", "--cmm-surfaces", "1", "--cmm-spacing",
                                         "0.5", "--cmm-search-mm", "0.1"}));
  EXPECT_EQ(1, r.exit_code) << r.err;
  EXPECT_NE(std::string::npos,
            r.err.find(" points found the surface of " + (out / "machined.stl").string() +
                       " within 0.1 mm along its normal: no measurement, " +
                       (out / "cmm.csv").string() + " not written"))
      << r.err;
  EXPECT_FALSE(fs::exists(out / "cmm.csv"));
  EXPECT_FALSE(fs::exists(out / "cmm.csv.tmp"));
  EXPECT_NE(std::string::npos,
            truecut({"run", "x.json", "p.ngc", "--help"}).out.find("--cmm-max-points"));
}

}  // namespace
