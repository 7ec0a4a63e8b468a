// `truecut part` writes a benchmark part that truecut's own interpreter reads.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "run_process.hpp"
#include "test_paths.hpp"
#include "truecut/offline/mesh_io.hpp"
#include "truecut/sim/machine_description.hpp"

using namespace truecut::test;

TEST(PartCli, WritesAllFilesAndTheProgramInterprets) {
  const auto out = scratch_dir() / "implant";
  auto r = run_process(
      {cli_path().string(), "part", "implant", "--out", out.string(), "--step-down", "4"});
  ASSERT_EQ(0, r.exit_code) << r.err;
  for (const char* f : {"nominal.stl", "program.ngc", "tools.tbl", "part.json", "machine.json",
                        "machine_ideal.json"})
    EXPECT_TRUE(std::filesystem::is_regular_file(out / f)) << f;
  auto canon =
      run_process({cli_path().string(), "canon", "--tool-table", (out / "tools.tbl").string(),
                   "--list-operations", (out / "program.ngc").string()});
  ASSERT_EQ(0, canon.exit_code) << canon.err;
  EXPECT_EQ("SHAFT_TOP_FACE\nSHAFT_PERIPHERAL\n", canon.out);
}

TEST(PartCli, Benchmark004WritesAllFilesTheProgramInterpretsAndTheMachineReadsBack) {
  const auto out = scratch_dir() / "benchmark004";
  auto r = run_process({cli_path().string(), "part", "benchmark004", "--out", out.string(),
                        "--mesh-edge", "3", "--stepover", "2", "--point-spacing", "2",
                        "--step-down", "5"});
  ASSERT_EQ(0, r.exit_code) << r.err;
  EXPECT_NE(std::string::npos, r.out.find("benchmark004: ")) << r.out;
  for (const char* f : {"nominal.stl", "program.ngc", "tools.tbl", "part.json", "machine.json",
                        "machine_ideal.json"})
    EXPECT_TRUE(std::filesystem::is_regular_file(out / f)) << f;
  auto canon =
      run_process({cli_path().string(), "canon", "--tool-table", (out / "tools.tbl").string(),
                   "--list-operations", (out / "program.ngc").string()});
  ASSERT_EQ(0, canon.exit_code) << canon.err;
  EXPECT_EQ("WALLS\nSTEP_FACES\nHEMISPHERE_3AXIS\nHEMISPHERE_CAP_5AXIS\n", canon.out);
  const auto machine = truecut::sim::read_machine_description(out / "machine.json");
  EXPECT_TRUE(machine.machine.effects.tool_radius_error.enabled);
  EXPECT_DOUBLE_EQ(machine.machine.effects.tool_radius_error.params.radius_mm, -0.1);
}

// Issue 24: --adapted regenerates benchmark004's program for an adapted
// geometry. Given the nominal itself, the passes stay on the nominal (as G1
// moves); a mesh of another part or another mesh edge is refused by name.
TEST(PartCli, AdaptedRegeneratesTheProgramAndRefusesAForeignMesh) {
  const auto root = scratch_dir();
  const auto part = [&](const std::string& name, const std::string& out,
                        std::vector<std::string> extra, const std::string& edge_mm = "3") {
    std::vector<std::string> args{cli_path().string(),
                                  "part",
                                  name,
                                  "--out",
                                  (root / out).string(),
                                  "--mesh-edge",
                                  edge_mm,
                                  "--stepover",
                                  "2",
                                  "--point-spacing",
                                  "2",
                                  "--step-down",
                                  "5"};
    args.insert(args.end(), extra.begin(), extra.end());
    return run_process(args);
  };
  ASSERT_EQ(0, part("benchmark004", "nominal", {}).exit_code);
  const std::string nominal_stl = (root / "nominal" / "nominal.stl").string();
  const auto r = part("benchmark004", "driven", {"--adapted", nominal_stl});
  ASSERT_EQ(0, r.exit_code) << r.err;
  EXPECT_NE(std::string::npos, r.out.find("found no facet (offset 0)")) << r.out;
  const std::string program = read_file(root / "driven" / "program.ngc");
  EXPECT_NE(std::string::npos, program.find("tool path driven by an adapted geometry"));
  EXPECT_EQ(std::string::npos, program.find("G2 X45.0000 Y0 Z15.0000 I-45.0000 J0"))
      << "the walls are G1 moves, not circles";
  EXPECT_EQ(read_file(root / "driven" / "nominal.stl"), read_file(root / "nominal" / "nominal.stl"))
      << "the nominal stays the nominal";

  const auto other_edge = part("benchmark004", "x", {"--adapted", nominal_stl}, "2");
  EXPECT_EQ(2, other_edge.exit_code);
  EXPECT_NE(std::string::npos, other_edge.err.find(nominal_stl + ": ")) << other_edge.err;
  EXPECT_NE(std::string::npos, other_edge.err.find("must come from this nominal"))
      << other_edge.err;
  const auto implant = part("implant", "y", {"--adapted", nominal_stl});
  EXPECT_EQ(2, implant.exit_code);
  EXPECT_NE(std::string::npos, implant.err.find("only benchmark004")) << implant.err;
  const auto missing = part("benchmark004", "z", {"--adapted", (root / "none.stl").string()});
  EXPECT_EQ(2, missing.exit_code);
  EXPECT_NE(std::string::npos, missing.err.find("none.stl")) << missing.err;
  for (const char* out : {"x", "y", "z"})
    EXPECT_FALSE(std::filesystem::exists(root / out)) << out;
}

TEST(PartCli, BadArgumentsAreUsageErrorsAndWriteNothing) {
  const auto out = scratch_dir() / "x";
  auto bogus = run_process({cli_path().string(), "part", "bogus", "--out", out.string()});
  EXPECT_EQ(2, bogus.exit_code);
  EXPECT_NE(std::string::npos, bogus.err.find("unknown part 'bogus'"));
  EXPECT_EQ(2, run_process({cli_path().string(), "part", "implant"}).exit_code) << "--out missing";
  EXPECT_EQ(2, run_process({cli_path().string(), "part", "implant", "--out", out.string(),
                            "--stepover", "0"})
                   .exit_code);
  EXPECT_FALSE(std::filesystem::exists(out));
}

// Issue 23: --stepover 0.001 (the documented minimum) and --stepover 100
// (inside the 0.001..100 then given) ended with exit 1 and a message about
// the PartOptions struct. The options take the ranges the generator takes.
TEST(PartCli, EachResolutionOptionIsRefusedOutsideItsOwnRange) {
  const auto out = scratch_dir() / "x";
  for (const auto& [option, value] :
       std::vector<std::pair<std::string, std::string>>{{"--stepover", "100"},
                                                        {"--mesh-edge", "50"},
                                                        {"--point-spacing", "11"},
                                                        {"--step-down", "20"},
                                                        {"--stepover", "0.0009"}}) {
    const auto r =
        run_process({cli_path().string(), "part", "implant", "--out", out.string(), option, value});
    EXPECT_EQ(2, r.exit_code) << option << " " << value << ": " << r.err;
    EXPECT_NE(std::string::npos, r.err.find(option + " " + value + " is outside ")) << r.err;
    EXPECT_EQ(std::string::npos, r.err.find("PartOptions")) << r.err;
  }
  EXPECT_FALSE(std::filesystem::exists(out));
  const auto at_max = run_process({cli_path().string(), "part", "implant", "--out", out.string(),
                                   "--mesh-edge", "4", "--stepover", "10", "--step-down", "17"});
  EXPECT_EQ(0, at_max.exit_code) << at_max.err;
}

// Issue 23: an "adapted" mesh 30 mm above the nominal gave a complete
// program, exit 0, with 72 % of the surface queries finding no facet.
TEST(PartCli, AnAdaptedMeshFarFromTheNominalIsRefused) {
  const auto root = scratch_dir();
  const std::vector<std::string> coarse = {"--mesh-edge",     "3", "--stepover",  "2",
                                           "--point-spacing", "2", "--step-down", "5"};
  auto part = [&](const std::string& out, std::vector<std::string> extra) {
    std::vector<std::string> args{cli_path().string(), "part", "benchmark004", "--out",
                                  (root / out).string()};
    args.insert(args.end(), coarse.begin(), coarse.end());
    args.insert(args.end(), extra.begin(), extra.end());
    return run_process(args);
  };
  ASSERT_EQ(0, part("nominal", {}).exit_code);
  truecut::offline::TriangleMesh up = truecut::offline::read_mesh(root / "nominal" / "nominal.stl");
  for (auto& v : up.vertices_mm)
    v.z() += 30.0;
  const std::string up30 = (root / "up30.stl").string();
  truecut::offline::write_mesh(up30, up);

  const auto far = part("far", {"--adapted", up30});
  EXPECT_EQ(2, far.exit_code) << far.err;
  EXPECT_NE(std::string::npos,
            far.err.find(up30 + " moves the nominal's surface by up to 30 mm, more than "
                                "--max-correction 0.2 mm"))
      << far.err;
  // Let through the move, and most queries find no facet.
  const auto misses = part("misses", {"--adapted", up30, "--max-correction", "50"});
  EXPECT_EQ(2, misses.exit_code) << misses.err;
  EXPECT_NE(std::string::npos, misses.err.find(" surface queries (")) << misses.err;
  EXPECT_NE(std::string::npos, misses.err.find("found no facet within 0.5 mm")) << misses.err;
  for (const char* out : {"far", "misses"})
    EXPECT_FALSE(std::filesystem::exists(root / out)) << out;
  EXPECT_EQ(2, part("x", {"--max-correction", "1"}).exit_code) << "without --adapted";
}

// The six files are written all or none: when the last cannot be written,
// the five before it are not left behind (they were, one by one).
TEST(PartCli, AFileThatCannotBeWrittenLeavesNoneOfTheSet) {
  const auto out = scratch_dir() / "implant";
  std::filesystem::create_directories(out / "machine_ideal.json");  // a folder in its way
  auto r = run_process(
      {cli_path().string(), "part", "implant", "--out", out.string(), "--step-down", "4"});
  EXPECT_NE(0, r.exit_code);
  EXPECT_NE(std::string::npos, r.err.find("machine_ideal.json")) << r.err;
  std::vector<std::string> left;
  for (const auto& e : std::filesystem::directory_iterator(out))
    left.push_back(e.path().filename().string());
  EXPECT_EQ(std::vector<std::string>{"machine_ideal.json"}, left) << "only the folder in the way";
}
