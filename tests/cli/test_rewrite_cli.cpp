// `truecut rewrite` as a user runs it: summary, output and audit record,
// and every kind of bad input (exit 2, a clear message, no output file).
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <fstream>
#include <regex>

#include "run_process.hpp"
#include "test_paths.hpp"

using namespace truecut::test;
namespace fs = std::filesystem;

namespace {

void write(const fs::path& p, const std::string& text) {
  std::ofstream(p, std::ios::binary) << text;
}

const char* kProgram =
    "%\n(OPERATION: FACE)\nG21 G17 G90 G94\nT2 M6\nG43 H2\nG0 X-8 Y-2 Z5\nG1 Z0 F200\n"
    "G1 X8 F600\nY2\nX-8\nG0 Z5\nM30\n%\n";

// Points on z = 0 over [-4, 4]^2 every 0.5 mm, compensation (0, 0, 0.05).
std::string face_matrix() {
  std::string csv =
      "# truecut compensation matrix v1\n# frame: workpiece\n# units: mm\n"
      "x,y,z,dx,dy,dz,valid,surface_id\n";
  for (int i = -8; i <= 8; ++i)
    for (int j = -8; j <= 8; ++j)
      csv += std::to_string(0.5 * i) + "," + std::to_string(0.5 * j) + ",0,0,0,0.05,1,5\n";
  return csv;
}

struct Case {
  fs::path dir;
  ProcessResult run(std::vector<std::string> args) const {
    args.insert(args.begin(), {cli_path().string(), "rewrite"});
    return run_process(args, dir);
  }
};

Case setup() {
  Case c{scratch_dir()};
  write(c.dir / "p.ngc", kProgram);
  write(c.dir / "tools.tbl", "T2 P2 D4 Z40\n");
  write(c.dir / "m.csv", face_matrix());
  return c;
}

// The tool radius is T2's in tools.tbl (D4: 2 mm).
const std::vector<std::string> kArgs = {"p.ngc",  "--matrix", "m.csv",   "--operation", "FACE",
                                        "--type", "face",     "--tools", "tools.tbl",   "--reach",
                                        "0.6",    "--out",    "out.ngc"};

std::vector<std::string> with(std::vector<std::string> args, const std::string& key,
                              const std::string& value) {
  for (size_t i = 0; i + 1 < args.size(); ++i)
    if (args[i] == key) {
      args[i + 1] = value;
      return args;
    }
  args.push_back(key);
  args.push_back(value);
  return args;
}

void expect_refused(const Case& c, const ProcessResult& r, const std::string& message) {
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
  EXPECT_EQ(r.out, "");
  EXPECT_FALSE(fs::exists(c.dir / "out.ngc"));
  EXPECT_FALSE(fs::exists(c.dir / "out.ngc.tmp"));
  EXPECT_FALSE(fs::exists(c.dir / "out.ngc.audit.json"));
}

// sha256 of out.ngc as `truecut rewrite` wrote it for kArgs plus
// `--tool-radius 2` when that option was required.
const char* kExplicitRadiusSha256 =
    "5ffb5ed66f709ce7aa57a3c986b92b14fc4e72313e22191548c36d503e3cf8dd";

}  // namespace

TEST(CliRewrite, WritesProgramSummaryAndAudit) {
  const Case c = setup();
  const auto r = c.run(kArgs);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("  moves read            6\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("  moves rewritten       2\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("  max compensation      0.0500 mm\n"), std::string::npos) << r.out;
  const std::string out = read_file(c.dir / "out.ngc");
  EXPECT_EQ(out.substr(0, out.find("X-7.5000")),
            "%\n(OPERATION: FACE)\nG21 G17 G90 G94\nT2 M6\nG43 H2\nG0 X-8 Y-2 Z5\nG1 Z0 F200\n");
  EXPECT_NE(out.find("X-6.5000 Y-2.0000 Z0.0500"), std::string::npos);
  EXPECT_FALSE(fs::exists(c.dir / "out.ngc.tmp"));
  // The audit record's digests are those of the files.
  const std::string audit = read_file(c.dir / "out.ngc.audit.json");
  auto sum = run_process({"/usr/bin/sha256sum", "out.ngc", "p.ngc", "m.csv", "tools.tbl"}, c.dir);
  ASSERT_EQ(sum.exit_code, 0);
  std::istringstream lines(sum.out);
  std::string digest, name;
  int n = 0;
  while (lines >> digest >> name) {
    EXPECT_NE(audit.find("\"sha256\": \"" + digest + "\""), std::string::npos) << name << audit;
    ++n;
  }
  EXPECT_EQ(n, 4);
  EXPECT_NE(audit.find("\"operation\": \"FACE\", \"type\": \"face\""), std::string::npos) << audit;
  EXPECT_NE(audit.find("\"placement\": \"every-pass\""), std::string::npos) << audit;
  EXPECT_NE(audit.find("\"smoothing_radius_mm\": 0"), std::string::npos) << audit;
  EXPECT_NE(audit.find("\"moves_rewritten\": 2"), std::string::npos) << audit;
  // The rewritten program runs through truecut's interpreter.
  auto canon =
      run_process({cli_path().string(), "canon", "--tool-table", "tools.tbl", "out.ngc"}, c.dir);
  EXPECT_EQ(canon.exit_code, 0) << canon.err;
}

// With the controller's parameter file the program runs where the machine
// runs it: G54 at X+100 puts the face pass 100 mm from a matrix measured
// at the program's coordinates, and onto one measured in the machine frame;
// the corrected points are written in the program's coordinates.
TEST(CliRewrite, ParameterFilePlacesTheProgramAsOnTheMachine) {
  const Case c = setup();
  write(c.dir / "m.var", "5220 1\n5221 100\n");
  expect_refused(c, c.run(with(kArgs, "--var-units", "cm")), "--var-units must be mm or inch");
  std::string shifted = face_matrix();
  std::regex first_column(R"(\n(-?[0-9.]+),)");
  std::string moved;
  std::smatch m;
  std::string rest = shifted;
  while (std::regex_search(rest, m, first_column)) {
    moved += m.prefix().str() + "\n" + std::to_string(std::stod(m[1].str()) + 100.0) + ",";
    rest = m.suffix().str();
  }
  moved += rest;
  write(c.dir / "m100.csv", moved);
  // The matrix at program coordinates no longer reaches the moves: refused.
  expect_refused(c, c.run(with(kArgs, "--var-file", "m.var")),
                 "no point of operation 'FACE' (6 moves) got a compensation");
  const auto on = c.run(with(with(kArgs, "--var-file", "m.var"), "--matrix", "m100.csv"));
  ASSERT_EQ(on.exit_code, 0) << on.err;
  EXPECT_NE(on.out.find("  moves rewritten       2\n"), std::string::npos) << on.out;
  const std::string out = read_file(c.dir / "out.ngc");
  EXPECT_NE(out.find("X-6.5000 Y-2.0000 Z0.0500"), std::string::npos) << out;
  const std::string audit = read_file(c.dir / "out.ngc.audit.json");
  EXPECT_NE(audit.find("\"role\": \"parameters\""), std::string::npos) << audit;
}

TEST(CliRewrite, UnknownOperation) {
  const Case c = setup();
  expect_refused(c, c.run(with(kArgs, "--operation", "ROUGH")),
                 "p.ngc: operation 'ROUGH' is not in the program (operations: FACE)");
}

TEST(CliRewrite, MatrixWithNaNOrWrongColumns) {
  const Case c = setup();
  write(c.dir / "nan.csv", "x,y,z,dx,dy,dz\n0,0,0,0,0,0.01\n0.5,0,0,NaN,0,0.01\n");
  expect_refused(c, c.run(with(kArgs, "--matrix", "nan.csv")), "nan.csv:3: dx is not finite (NaN)");
  write(c.dir / "cols.csv", "# c\nx,y,z,u,v,w\n0,0,0,0,0,0.01\n");
  expect_refused(c, c.run(with(kArgs, "--matrix", "cols.csv")),
                 "cols.csv:2: header has no column 'dx'");
  write(c.dir / "short.csv", "x,y,z,dx,dy,dz\n0,0,0,0,0\n");
  expect_refused(c, c.run(with(kArgs, "--matrix", "short.csv")),
                 "short.csv:2: 5 fields, the header has 6");
  expect_refused(c, c.run(with(kArgs, "--matrix", "missing.csv")),
                 "missing.csv: cannot open the compensation matrix");
}

TEST(CliRewrite, StepMustBePositive) {
  const Case c = setup();
  expect_refused(c, c.run(with(kArgs, "--step", "0")), "--step must be > 0 mm (got 0)");
  expect_refused(c, c.run(with(kArgs, "--step", "-0.5")), "--step must be > 0 mm (got -0.5)");
  expect_refused(c, c.run(with(kArgs, "--step", "abc")), "--step 'abc' is not a number");
}

TEST(CliRewrite, UnsupportedWordNamesTheLine) {
  const Case c = setup();
  std::string prog = kProgram;
  prog.replace(prog.find("G1 X8 F600"), 10, "G1 X8 F600 M0");
  write(c.dir / "p.ngc", prog);
  expect_refused(c, c.run(kArgs), "p.ngc:8:12: M0 beside a move: this move cannot be rewritten");
  prog = kProgram;
  prog.replace(prog.find("G1 X8 F600"), 10, "G1 X8 F600 M62 P1");
  write(c.dir / "p.ngc", prog);
  expect_refused(c, c.run(kArgs), "p.ngc:8:12: M62 beside a move");
}

TEST(CliRewrite, UsageErrors) {
  const Case c = setup();
  expect_refused(c, c.run(with(kArgs, "--field", "f.tcf")),
                 "give exactly one of --matrix and --field");
  expect_refused(c, c.run(with(kArgs, "--type", "drill")), "expected peripheral, face or ball");
  std::vector<std::string> no_out(kArgs.begin(), kArgs.end() - 2);
  expect_refused(c, c.run(no_out), "--out OUT.ngc is required");
  std::vector<std::string> field = with(kArgs, "--matrix", "x");
  field.erase(field.begin() + 1, field.begin() + 3);
  field.erase(std::find(field.begin(), field.end(), "--reach"),
              std::find(field.begin(), field.end(), "--reach") + 2);  // matrix only
  write(c.dir / "f.tcf", "not a field\n");
  expect_refused(c, c.run(with(field, "--field", "f.tcf")), "f.tcf");
  // An output that is not a regular file is not replaced.
  fs::create_directory(c.dir / "dir.ngc");
  const auto r = c.run(with(kArgs, "--out", "dir.ngc"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("dir.ngc: exists and is not a regular file"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::is_directory(c.dir / "dir.ngc"));
  EXPECT_FALSE(fs::exists(c.dir / "dir.ngc.tmp"));
  // Nor is the audit record's, and then the program is not written either.
  fs::create_directory(c.dir / "out.ngc.audit.json");
  const auto audit = c.run(kArgs);
  EXPECT_EQ(audit.exit_code, 2);
  EXPECT_NE(audit.err.find("out.ngc.audit.json: exists and is not a regular file"),
            std::string::npos)
      << audit.err;
  EXPECT_FALSE(fs::exists(c.dir / "out.ngc"));
  EXPECT_FALSE(fs::exists(c.dir / "out.ngc.tmp"));
  fs::remove(c.dir / "out.ngc.audit.json");
  expect_refused(c, c.run(with(kArgs, "--placement", "nearest")), "expected every-pass or tip");
  expect_refused(c, c.run(with(kArgs, "--smooth", "-1")), "--smooth -1 is outside");
  expect_refused(c, c.run(with(kArgs, "--cutting-length", "0")), "--cutting-length 0 is outside");
}

TEST(CliRewrite, ToolRadiusFromTheTableGivesTheOutputOfTheExplicitRadius) {
  const Case c = setup();
  ASSERT_EQ(c.run(kArgs).exit_code, 0);
  const std::string from_table = read_file(c.dir / "out.ngc");
  const std::string audit = read_file(c.dir / "out.ngc.audit.json");
  EXPECT_NE(audit.find("\"tool_radius_mm\": 2,"), std::string::npos) << audit;
  EXPECT_NE(audit.find("\"tools\": [{\"tool\": 2, \"radius_mm\": 2}]"), std::string::npos) << audit;
  // The digest of what `--tool-radius 2` wrote before the radius came from
  // the tool table.
  auto sum = run_process({"/usr/bin/sha256sum", "out.ngc"}, c.dir);
  ASSERT_EQ(sum.exit_code, 0);
  EXPECT_EQ(sum.out.substr(0, 64), kExplicitRadiusSha256);
  // The same radius given by hand: a check, the same bytes.
  const auto r = c.run(with(kArgs, "--tool-radius", "2"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("operation FACE (face, R 2 mm, step 0.5 mm"), std::string::npos) << r.out;
  EXPECT_EQ(read_file(c.dir / "out.ngc"), from_table);
}

TEST(CliRewrite, ToolRadiusThatDiffersFromTheTableIsRefused) {
  const Case c = setup();
  expect_refused(c, c.run(with(kArgs, "--tool-radius", "1.5")),
                 "truecut rewrite: the tool radius given (1.5 mm) differs from the tool table's "
                 "for tool T2 (D 4 mm, radius 2 mm; first used on p.ngc:7)");
}

TEST(CliRewrite, ToolTableIsRequiredAndMustHoldTheTool) {
  const Case c = setup();
  std::vector<std::string> no_tools = kArgs;
  no_tools.erase(no_tools.begin() + 7, no_tools.begin() + 9);
  expect_refused(c, c.run(no_tools), "--tools FILE is required");
  write(c.dir / "t1.tbl", "T1 P1 D2 Z30\n");
  expect_refused(c, c.run(with(kArgs, "--tools", "t1.tbl")),
                 "p.ngc:4:1: tool T2 is not in the tool table");
  // No tool in the spindle for the operation's moves.
  std::string prog = kProgram;
  prog.replace(prog.find("T2 M6\nG43 H2\n"), 13, "");
  write(c.dir / "p.ngc", prog);
  expect_refused(c, c.run(kArgs),
                 "p.ngc:5: feed move of operation 'FACE' with no tool in the spindle");
}

TEST(CliRewrite, Help) {
  auto r = run_process({cli_path().string(), "rewrite", "--help"});
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("usage: truecut rewrite IN.ngc"), std::string::npos);
  auto list = run_process({cli_path().string(), "--help"});
  EXPECT_NE(list.out.find("rewrite"), std::string::npos);
}

// A matrix or field that reaches none of the operation's points (another
// part, frame or unit) is refused, nothing written; --force writes the
// program unchanged, says so and records it.
TEST(CliRewrite, ACompensationThatReachesNoPointIsRefusedUnlessForced) {
  const Case c = setup();
  // The face matrix 1 m away along x.
  std::string far =
      "# truecut compensation matrix v1\n# frame: workpiece\n# units: mm\n"
      "x,y,z,dx,dy,dz,valid,surface_id\n";
  for (int i = -8; i <= 8; ++i)
    for (int j = -8; j <= 8; ++j)
      far += std::to_string(1000 + 0.5 * i) + "," + std::to_string(0.5 * j) + ",0,0,0,0.05,1,5\n";
  write(c.dir / "far.csv", far);
  expect_refused(c, c.run(with(kArgs, "--matrix", "far.csv")),
                 "the matrix far.csv does not reach its moves");
  std::vector<std::string> forced = with(kArgs, "--matrix", "far.csv");
  forced.push_back("--force");
  const auto r = c.run(forced);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("WARNING: no point of the operation got a compensation"), std::string::npos)
      << r.err;
  EXPECT_EQ(read_file(c.dir / "out.ngc"), kProgram);
  EXPECT_NE(read_file(c.dir / "out.ngc.audit.json").find("\"forced\": true"), std::string::npos);
}

// Options that only the matrix's neighbour search reads are refused with a
// field, instead of being recorded in the audit as if they had acted.
TEST(CliRewrite, MatrixOnlyOptionsAreRefusedWithAField) {
  const Case c = setup();
  for (const auto& [option, value] :
       std::vector<std::pair<std::string, std::string>>{{"--smooth", "5"},
                                                        {"--surfaces", "7"},
                                                        {"--placement", "tip"},
                                                        {"--reach", "0.6"},
                                                        {"--cutting-length", "3"}}) {
    std::vector<std::string> args = {"p.ngc",   "--field", "f.tcf",   "--operation", "FACE",
                                     "--type",  "face",    "--tools", "tools.tbl",   "--out",
                                     "out.ngc", option,    value};
    expect_refused(c, c.run(args), option + " goes with --matrix");
  }
}

// A surface id beyond int32 would wrap onto another surface (4294967297 was
// surface 1).
TEST(CliRewrite, SurfaceIdsBeyondTheirRangeAreRefused) {
  const Case c = setup();
  expect_refused(c, c.run(with(kArgs, "--surfaces", "4294967297")),
                 "--surfaces: 4294967297 is outside the surface ids 0..2147483647");
  expect_refused(c, c.run(with(kArgs, "--surfaces", "99999999999999999999")),
                 "is outside the surface ids");
  expect_refused(c, c.run(with(kArgs, "--surfaces", "-1")), "is outside the surface ids");
}

// A file name (or an operation name) that is not UTF-8 still gives an audit
// record that is JSON: a byte that is not UTF-8 is written as U+FFFD.
TEST(CliRewrite, TheAuditIsJsonForANameThatIsNotUtf8) {
  const Case c = setup();
  const std::string latin1 = "caf\xe9.ngc";
  write(c.dir / latin1, kProgram);
  std::vector<std::string> args = kArgs;
  args[0] = latin1;
  const auto q = c.run(args);
  ASSERT_EQ(q.exit_code, 0) << q.err;
  const std::string audit = read_file(c.dir / "out.ngc.audit.json");
  EXPECT_NE(audit.find("\"path\": \"caf\\ufffd.ngc\""), std::string::npos) << audit;
  EXPECT_EQ(audit.find('\xe9'), std::string::npos) << "a raw Latin-1 byte is not JSON";
}

// Progress is for a terminal: with stderr a pipe, a rewrite says nothing
// there, and --quiet is accepted as by every other command.
TEST(CliRewrite, NoProgressOffATerminalAndQuietIsAccepted) {
  const Case c = setup();
  for (const bool quiet : {false, true}) {
    std::vector<std::string> args = kArgs;
    if (quiet) args.push_back("--quiet");
    const auto r = c.run(args);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(r.err, "");
  }
}
