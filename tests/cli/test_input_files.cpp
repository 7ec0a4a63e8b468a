// Input files that are not files a reader can finish (issue 23): a device
// that never ends (/dev/zero used to make canon, run, diagnose and iso230
// read until memory ran out), a folder, a file over the input budget. Each
// is refused at once with exit code 2 and a message naming the file.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "run_process.hpp"
#include "test_paths.hpp"

using namespace truecut::test;
namespace fs = std::filesystem;

namespace {

// `truecut <args>` where "{}" stands for the input under test.
struct Reader {
  const char* name;
  std::vector<std::string> args;
};

std::vector<Reader> readers(const fs::path& out) {
  const std::string o = out.string();
  return {
      {"G-code program", {"canon", "{}"}},
      {".hal file", {"run", "{}", "--dry-run"}},
      {"recording (diagnose)", {"diagnose", "--recording", "{}", "--out", o + "/d"}},
      {"recording (iso230)", {"iso230", "--recording", "{}", "--out", o + "/i"}},
  };
}

ProcessResult run_with(const std::vector<std::string>& env, const Reader& r,
                       const std::string& input) {
  std::vector<std::string> argv = {"/usr/bin/env"};
  argv.insert(argv.end(), env.begin(), env.end());
  argv.push_back(cli_path().string());
  for (const auto& a : r.args)
    argv.push_back(a == "{}" ? input : a);
  return run_process(argv);
}

}  // namespace

TEST(InputFiles, ADeviceIsRefusedNotReadWithoutEnd) {
  if (!fs::exists("/dev/zero")) GTEST_SKIP() << "no /dev/zero on this system";
  const fs::path out = scratch_dir();
  for (const Reader& r : readers(out)) {
    const ProcessResult p = run_with({}, r, "/dev/zero");
    EXPECT_EQ(2, p.exit_code) << r.name << ": " << p.err;
    EXPECT_NE(std::string::npos, p.err.find("/dev/zero: is not a regular file")) << p.err;
  }
}

TEST(InputFiles, AFolderIsRefused) {
  const fs::path out = scratch_dir();
  for (const Reader& r : readers(out)) {
    const ProcessResult p = run_with({}, r, out.string());
    EXPECT_EQ(2, p.exit_code) << r.name << ": " << p.err;
    EXPECT_NE(std::string::npos, p.err.find(out.string() + ": is a folder")) << p.err;
  }
}

TEST(InputFiles, AFileOverTheBudgetIsRefusedNamingTheBudget) {
  const fs::path out = scratch_dir();
  const fs::path big = out / "big.txt";
  {
    std::ofstream f(big, std::ios::binary);
    const std::string line = "; a comment line of a large file\n";
    for (std::size_t n = 0; n < (2u << 20) / line.size() + 1; ++n)
      f << line;
  }
  for (const Reader& r : readers(out)) {
    const ProcessResult p = run_with({"TRUECUT_MAX_INPUT_MB=1"}, r, big.string());
    EXPECT_EQ(2, p.exit_code) << r.name << ": " << p.err;
    EXPECT_NE(std::string::npos, p.err.find("2 MB is more than the 1 MB an input file may have"))
        << p.err;
    EXPECT_NE(std::string::npos, p.err.find("TRUECUT_MAX_INPUT_MB")) << p.err;
  }
  // Raised, the same file is read (and refused for what it holds, if at all).
  const ProcessResult canon = run_with({"TRUECUT_MAX_INPUT_MB=4"}, readers(out)[0], big.string());
  EXPECT_EQ(std::string::npos, canon.err.find("an input file may have")) << canon.err;
}

TEST(InputFiles, ARecordingWithOnlyAHeaderIsRefused) {
  // `truecut diagnose` used to crash on it (signal 11).
  const fs::path out = scratch_dir();
  const fs::path header_only = out / "header.csv";
  std::ofstream(header_only) << "t,x_cmd,x_act\n";
  for (const Reader& r : readers(out)) {
    if (r.args[0] != "diagnose" && r.args[0] != "iso230") continue;
    const ProcessResult p = run_with({}, r, header_only.string());
    EXPECT_EQ(2, p.exit_code) << r.name << ": " << p.err;
    EXPECT_NE(std::string::npos, p.err.find("header.csv: a header and no data rows")) << p.err;
  }
}

TEST(InputFiles, ARecordingWithImpossibleValuesIsRefusedAtItsCell) {
  // `truecut diagnose` ran on values of 1e154 (their squares overflow) and
  // `iso230` took a target G of 1e30: both exited 0.
  const fs::path out = scratch_dir();
  struct Case {
    const char* file;
    const char* row;       // the 31st data row (line 32)
    const char* expected;  // in the message
  };
  const Case cases[] = {
      {"huge_x.csv", "0.03,0.5,1e154", "huge_x.csv:32: column 3 'x_act': 1e+154 mm is outside"},
      {"target.csv", "0.03,1e30,0.5", "target.csv:32: column 2 'x_cmd': 1e+30 mm is outside"},
      {"time.csv", "3e9,0.5,0.5", "time.csv:32: column 1 't': 3e+09 s is outside"},
  };
  for (const Case& c : cases) {
    const fs::path file = out / c.file;
    {
      std::ofstream f(file);
      f << "t,x_cmd,x_act\n";
      for (int i = 0; i < 30; ++i)
        f << i * 1e-3 << "," << (i % 10) * 0.1 << "," << (i % 10) * 0.1 << "\n";
      f << c.row << "\n";
      for (int i = 31; i < 60; ++i)
        f << (i + 1) * 1e-3 << ",0.5,0.5\n";
    }
    for (const Reader& r : readers(out)) {
      if (r.args[0] != "diagnose" && r.args[0] != "iso230") continue;
      const ProcessResult p = run_with({}, r, file.string());
      EXPECT_EQ(2, p.exit_code) << r.name << ": " << p.err;
      EXPECT_NE(std::string::npos, p.err.find(c.expected)) << r.name << ": " << p.err;
    }
  }
}

TEST(InputFiles, AnOutputThatIsAnInputIsRefusedAndTheInputKept) {
  // Issue 23: an output path equal to an input path was accepted.
  const fs::path dir = scratch_dir();
  ASSERT_EQ(
      0, run_process({cli_path().string(), "part", "implant", "--mesh-edge", "2", "--stepover", "2",
                      "--point-spacing", "2", "--step-down", "4", "--out", (dir / "p").string()})
             .exit_code);
  const std::string nominal = (dir / "p" / "nominal.stl").string();
  const std::string program = (dir / "p" / "program.ngc").string();
  const std::string link = (dir / "link.stl").string();
  fs::create_symlink(nominal, link);
  const auto before = fs::file_size(nominal);
  struct Case {
    std::vector<std::string> args;
    std::string says;
  };
  const std::vector<Case> cases = {
      {{"cmm", nominal, "--nominal", nominal, "--part", (dir / "p" / "part.json").string(), "--out",
        link},
       "--out " + link + " is the input " + nominal},
      {{"scan", nominal, "--out", (dir / "s.ply").string(), "--mesh-out", link},
       "--mesh-out " + link + " is the input " + nominal},
      {{"rewrite", program, "--field", (dir / "none.tcf").string(), "--operation", "X", "--type",
        "face", "--tools", (dir / "p" / "tools.tbl").string(), "--out", program},
       "--out " + program + " is the input " + program},
  };
  for (const Case& c : cases) {
    std::vector<std::string> argv = {cli_path().string()};
    argv.insert(argv.end(), c.args.begin(), c.args.end());
    const ProcessResult p = run_process(argv);
    EXPECT_EQ(2, p.exit_code) << c.args[0] << ": " << p.err;
    EXPECT_NE(std::string::npos, p.err.find(c.says)) << p.err;
  }
  EXPECT_EQ(before, fs::file_size(nominal));
  EXPECT_TRUE(fs::is_regular_file(program));
  EXPECT_FALSE(fs::exists(dir / "s.ply"));
}

// `truecut part --mesh-edge 0.002` tried to build hundreds of millions of
// triangles (15 s and 1.6 GB before it was stopped); it is refused at once
// with the estimate and the option that raises the budget, and a mesh edge
// within a lowered budget passes.
TEST(InputFiles, APartMeshOverTheTriangleBudgetIsRefusedAtOnce) {
  const fs::path dir = scratch_dir();
  ProcessResult r = run_process({cli_path().string(), "part", "implant", "--out",
                                 (dir / "a").string(), "--mesh-edge", "0.002"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--mesh-edge 0.002 mm would make about"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--max-triangles 20000000"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "a"));
  r = run_process({cli_path().string(), "part", "implant", "--out", (dir / "b").string(),
                   "--mesh-edge", "0.5", "--max-triangles", "100"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--max-triangles 100;"), std::string::npos) << r.err;
  r = run_process({cli_path().string(), "part", "implant", "--out", (dir / "c").string(),
                   "--mesh-edge", "0.5", "--max-triangles", "100000"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
}
