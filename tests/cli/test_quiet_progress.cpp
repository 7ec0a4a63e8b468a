// Progress goes to a terminal only, and --quiet leaves nothing on stderr but
// warnings and errors, for every command alike (issue 23: `run`, `scan` and
// `diagnose` wrote their progress into log files; seven commands refused
// --quiet).
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>
#include <vector>

#include "run_process.hpp"
#include "test_paths.hpp"

using namespace truecut::test;

namespace {

std::vector<std::string> truecut_args(std::vector<std::string> args) {
  args.insert(args.begin(), cli_path().string());
  return args;
}

// A small implant part (program, nominal, part.json, machine) in `dir`/part.
std::filesystem::path small_part(const std::filesystem::path& dir) {
  const auto part = dir / "part";
  const auto r = run_process(truecut_args({"part", "implant", "--out", part.string(), "--mesh-edge",
                                           "4", "--stepover", "5", "--step-down", "10"}));
  EXPECT_EQ(0, r.exit_code) << r.err;
  return part;
}

bool contains(const std::string& text, const std::string& what) {
  return text.find(what) != std::string::npos;
}

}  // namespace

TEST(QuietProgress, MachiningShowsItsProgressOnATerminalOnly) {
  const auto dir = scratch_dir();
  const auto part = small_part(dir);
  auto run = [&](const std::string& out, bool terminal, bool quiet) {
    std::vector<std::string> args = {"run",
                                     (part / "machine.json").string(),
                                     (part / "program.ngc").string(),
                                     "--dexel-spacing",
                                     "1",
                                     "--out",
                                     (dir / out).string(),
                                     "--scan",
                                     "scan.ply",
                                     "--scan-density",
                                     "1",
                                     "--cmm",
                                     "cmm.csv"};
    if (quiet) args.push_back("--quiet");
    return terminal ? run_process_on_a_terminal(truecut_args(args))
                    : run_process(truecut_args(args));
  };
  // The program runs 12.5 s: a report for each second, on one line.
  const auto shown = run("tty", true, false);
  ASSERT_EQ(0, shown.exit_code) << shown.err;
  EXPECT_TRUE(contains(shown.err, "\r  12.0 / 12.5 s ( 96%)")) << shown.err;
  EXPECT_TRUE(contains(shown.err, "scan: pose 5/5")) << shown.err;
  EXPECT_TRUE(contains(shown.err, "cmm: probing")) << shown.err;

  const auto logged = run("log", false, false);
  ASSERT_EQ(0, logged.exit_code) << logged.err;
  EXPECT_FALSE(contains(logged.err, " / 12.5 s")) << logged.err;
  EXPECT_FALSE(contains(logged.err, "scan: pose")) << logged.err;
  EXPECT_FALSE(contains(logged.err, "cmm: probing")) << logged.err;
  // What is not progress stays: what ran and what the components wrote.
  EXPECT_TRUE(contains(logged.err, "machining ")) << logged.err;
  EXPECT_TRUE(contains(logged.err, "recorder.0: wrote")) << logged.err;

  for (const bool terminal : {false, true}) {
    const auto quiet = run(terminal ? "quiet_tty" : "quiet_log", terminal, true);
    ASSERT_EQ(0, quiet.exit_code) << quiet.err;
    EXPECT_EQ(quiet.err, "");
    EXPECT_TRUE(contains(quiet.out, "machined in")) << quiet.out;  // the summary is on stdout
  }
}

TEST(QuietProgress, AHalRunShowsItsProgressOnATerminalOnly) {
  const auto dir = scratch_dir();
  const std::string circle = (source_dir() / "examples" / "circle").string();
  auto run = [&](bool terminal, bool quiet) {
    std::vector<std::string> args = {
        "run",   circle + "/circle.hal", "--ini", circle + "/circle.ini", "--time", "2.5",
        "--out", (dir / "out").string()};
    if (quiet) args.push_back("--quiet");
    return terminal ? run_process_on_a_terminal(truecut_args(args))
                    : run_process(truecut_args(args));
  };
  const auto shown = run(true, false);
  ASSERT_EQ(0, shown.exit_code) << shown.err;
  EXPECT_TRUE(contains(shown.err, "\r  2.0 / 2.5 s ( 80%)")) << shown.err;
  const auto logged = run(false, false);
  ASSERT_EQ(0, logged.exit_code) << logged.err;
  EXPECT_FALSE(contains(logged.err, " / 2.5 s")) << logged.err;
  const auto quiet = run(true, true);
  ASSERT_EQ(0, quiet.exit_code) << quiet.err;
  EXPECT_EQ(quiet.err, "");
}

TEST(QuietProgress, EveryMeasuringCommandTakesQuiet) {
  const auto dir = scratch_dir();
  const auto part = small_part(dir);
  const std::string nominal = (part / "nominal.stl").string();
  const auto scan_tty = run_process_on_a_terminal(
      truecut_args({"scan", nominal, "--out", (dir / "a.ply").string(), "--density", "1"}));
  ASSERT_EQ(0, scan_tty.exit_code) << scan_tty.err;
  EXPECT_TRUE(contains(scan_tty.err, "scan: pose 5/5")) << scan_tty.err;
  for (const auto& args : std::vector<std::vector<std::string>>{
           {"scan", nominal, "--out", (dir / "b.ply").string(), "--density", "1"},
           {"cmm", nominal, "--nominal", nominal, "--part", (part / "part.json").string(), "--out",
            (dir / "cmm.csv").string()}}) {
    const auto logged = run_process(truecut_args(args));
    ASSERT_EQ(0, logged.exit_code) << logged.err;
    EXPECT_EQ(logged.err, "") << args[0];
    std::vector<std::string> quiet = args;
    quiet.push_back("--quiet");
    const auto on_terminal = run_process_on_a_terminal(truecut_args(quiet));
    ASSERT_EQ(0, on_terminal.exit_code) << on_terminal.err;
    EXPECT_EQ(on_terminal.err, "") << args[0];
  }
  // diagnose and iso230 take --quiet (their progress: test_diagnosis_cli).
  for (const char* command : {"diagnose", "iso230"}) {
    const auto r = run_process(truecut_args({command, "--help"}));
    EXPECT_TRUE(contains(r.out, "--quiet")) << command;
  }
}

// The stage line of `part`, `field`, `rewrite` and of `run` while it loads
// (cli/stage_progress.hpp), drawn at once with TRUECUT_PROGRESS_AFTER_S=0
// (otherwise after a second): on a terminal, not in a log, not with --quiet.
TEST(QuietProgress, StagesAreShownOnATerminalOnly) {
  const auto dir = scratch_dir();
  ASSERT_EQ(0, setenv("TRUECUT_PROGRESS_AFTER_S", "0", 1));
  auto part = [&](const std::string& name, bool terminal, bool quiet) {
    std::vector<std::string> args = {"part",        "implant", "--out",      (dir / name).string(),
                                     "--mesh-edge", "4",       "--stepover", "5",
                                     "--step-down", "10"};
    if (quiet) args.push_back("--quiet");
    return terminal ? run_process_on_a_terminal(truecut_args(args))
                    : run_process(truecut_args(args));
  };
  const auto shown = part("tty", true, false);
  const auto logged = part("log", false, false);
  const auto quiet = part("quiet", true, true);
  const auto run = run_process_on_a_terminal(truecut_args(
      {"run", (dir / "tty" / "machine.json").string(), (dir / "tty" / "program.ngc").string(),
       "--dexel-spacing", "1", "--out", (dir / "run").string()}));
  unsetenv("TRUECUT_PROGRESS_AFTER_S");
  ASSERT_EQ(0, shown.exit_code) << shown.err;
  EXPECT_TRUE(contains(shown.err, "\rtruecut part: ")) << shown.err;
  ASSERT_EQ(0, logged.exit_code) << logged.err;
  EXPECT_FALSE(contains(logged.err, "truecut part: ")) << logged.err;
  ASSERT_EQ(0, quiet.exit_code) << quiet.err;
  EXPECT_EQ(quiet.err, "");
  ASSERT_EQ(0, run.exit_code) << run.err;
  EXPECT_TRUE(contains(run.err, "\rtruecut run: reading, checking and planning the program"))
      << run.err;
  // The cutting model's message at load comes below that line, not in it.
  EXPECT_TRUE(contains(run.err, ")\r\ncutting: info: cut: ")) << run.err;
}
