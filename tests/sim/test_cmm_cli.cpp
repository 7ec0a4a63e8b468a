// `truecut cmm`: probing a benchmark part's compensated surfaces, a point
// file, and input errors that exit 2 without writing anything.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <fstream>
#include <sstream>

#include "run_process.hpp"
#include "test_paths.hpp"

using namespace truecut::test;

namespace {

std::filesystem::path implant(const std::filesystem::path& dir) {
  const auto part = dir / "implant";
  const auto r = run_process({cli_path().string(), "part", "implant", "--out", part.string(),
                              "--mesh-edge", "2", "--step-down", "4"});
  EXPECT_EQ(0, r.exit_code) << r.err;
  return part;
}

ProcessResult cmm_cli(std::vector<std::string> args) {
  args.insert(args.begin(), {cli_path().string(), "cmm"});
  return run_process(args);
}

}  // namespace

TEST(CmmCli, ProbesTheCompensatedSurfacesOfAPart) {
  const auto dir = scratch_dir();
  const auto part = implant(dir);
  const auto nominal = (part / "nominal.stl").string();
  const auto out = dir / "cmm.csv";
  auto r = cmm_cli({nominal, "--nominal", nominal, "--part", (part / "part.json").string(),
                    "--spacing", "0.5", "--out", out.string()});
  ASSERT_EQ(0, r.exit_code) << r.err;
  // One row per compensated surface (1–5) plus "all".
  for (const char* row : {"\n1 ", "\n2 ", "\n3 ", "\n4 ", "\n5 ", "\nall "})
    EXPECT_NE(std::string::npos, r.out.find(row)) << row << "\n" << r.out;
  EXPECT_EQ(std::string::npos, r.out.find("\n6 ")) << r.out;
  const std::string csv = read_file(out);
  EXPECT_EQ(0u, csv.find("x,y,z,nx,ny,nz,surface,deviation_mm,valid\n"));

  // The written CSV is a valid point list; --surfaces picks the top only.
  auto again = cmm_cli({nominal, "--points", out.string(), "--out", (dir / "again.csv").string()});
  ASSERT_EQ(0, again.exit_code) << again.err;
  auto top = cmm_cli({nominal, "--nominal", nominal, "--part", (part / "part.json").string(),
                      "--surfaces", "5", "--out", (dir / "top.csv").string()});
  ASSERT_EQ(0, top.exit_code) << top.err;
  EXPECT_NE(std::string::npos, top.out.find("\n5 "));
  EXPECT_EQ(std::string::npos, top.out.find("\n1 "));
}

TEST(CmmCli, BadInputExitsTwoAndWritesNothing) {
  const auto dir = scratch_dir();
  const auto part = implant(dir);
  const auto nominal = (part / "nominal.stl").string();
  const auto json = (part / "part.json").string();
  const auto out = (dir / "cmm.csv").string();
  std::ofstream(dir / "bad_points.csv") << "0 0 17 0 0 1 5\n0 0 17 0 0 1 5\n0 0 17 0 0\n";
  {
    std::ofstream(dir / "short.json") << R"({"surfaces": [{"id": 5, "compensate": true}],
                                           "triangle_surface_ids": [5, 5]})";
  }
  struct Case {
    std::vector<std::string> args;
    std::string message;
  };
  const std::vector<Case> cases = {
      {{nominal, "--points", (dir / "bad_points.csv").string(), "--out", out},
       "bad_points.csv:3: expected 6 or 7 values"},
      {{nominal, "--nominal", nominal, "--part", (dir / "short.json").string(), "--out", out},
       "short.json: key 'triangle_surface_ids' has 2 entries"},
      {{nominal, "--nominal", nominal, "--part", json, "--surfaces", "5,99", "--out", out},
       "no surface 99"},
      {{nominal, "--nominal", nominal, "--part", json, "--surfaces", "5,x", "--out", out},
       "'x' is not a surface id"},
      {{nominal, "--nominal", nominal, "--out", out}, "give --nominal and --part, or --points"},
      {{nominal, "--nominal", nominal, "--part", json, "--out", out, "--sigma-um", "30"},
       "--sigma-um 30 is outside"},
      {{(dir / "none.stl").string(), "--nominal", nominal, "--part", json, "--out", out},
       "none.stl"},
  };
  for (const Case& c : cases) {
    const auto r = cmm_cli(c.args);
    EXPECT_EQ(2, r.exit_code) << c.message << "\n" << r.err;
    EXPECT_NE(std::string::npos, r.err.find(c.message)) << r.err;
  }
  EXPECT_FALSE(std::filesystem::exists(out));
  EXPECT_FALSE(std::filesystem::exists(out + ".tmp"));

  const auto fifo = dir / "fifo.csv";
  ASSERT_EQ(0, ::mkfifo(fifo.c_str(), 0600));
  const auto r = cmm_cli({nominal, "--nominal", nominal, "--part", json, "--out", fifo.string()});
  EXPECT_EQ(2, r.exit_code);
  EXPECT_NE(std::string::npos, r.err.find("not a regular file")) << r.err;
  EXPECT_TRUE(std::filesystem::is_fifo(fifo));
}
