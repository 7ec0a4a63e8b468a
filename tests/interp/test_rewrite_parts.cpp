// `truecut rewrite` on every operation of the benchmark parts (implant,
// freeform, benchmark004): the rewritten programs are accepted by truecut's
// interpreter and by LinuxCNC's standalone rs274 (fetched as for the oracle
// test), and both read them call for call alike.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>

#include "rs274_compare.hpp"
#include "run_process.hpp"
#include "test_paths.hpp"

namespace truecut::interp::testing {
namespace {

namespace fs = std::filesystem;
using truecut::test::binary_dir;
using truecut::test::cli_path;
using truecut::test::read_file;
using truecut::test::run_process;
using truecut::test::scratch_dir;
using truecut::test::source_dir;

void write(const fs::path& p, const std::string& text) {
  std::ofstream(p, std::ios::binary) << text;
}

// rs274 (a wrapper script), or the reason it cannot be had.
const fs::path* rs274(std::string& why) {
  static std::string reason;
  static const std::optional<fs::path> path = []() -> std::optional<fs::path> {
    const fs::path dir = binary_dir() / "rs274-oracle";
    auto r = run_process(
        {"/bin/bash", (source_dir() / "tests/interp/fetch_rs274.sh").string(), dir.string()});
    if (r.exit_code != 0) {
      reason = r.err.empty() ? "fetch_rs274.sh failed" : r.err;
      return std::nullopt;
    }
    return dir / "rs274";
  }();
  why = reason;
  return path ? &*path : nullptr;
}

// rs274 without an INI file reads tool tables in inches.
std::string inch_tools(const std::string& mm) {
  static const std::regex word(R"(([XYZDxyzd])(-?[0-9.]+))");
  std::istringstream in(mm);
  std::string line, out;
  while (std::getline(in, line)) {
    const size_t semi = line.find(';');
    std::string code = line.substr(0, semi), rest;
    std::smatch m;
    while (std::regex_search(code, m, word)) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "%s%.6f", m[1].str().c_str(), std::stod(m[2]) / 25.4);
      rest += m.prefix().str() + buf;
      code = m.suffix();
    }
    out += rest + code + "\n";
  }
  return out;
}

// The Sinumerik TRAORI/TRAFOOF lines mean nothing to rs274: dropped for both.
std::string without_sinumerik(const std::string& text) {
  static const std::regex word(R"(\b(TRAORI|TRAFOOF)\b)");
  return std::regex_replace(text, word, "");
}

// A compensation matrix on the operation's own programmed points (every 4th
// move of `truecut canon --operation`; XY-plane arcs give their end), with a
// smooth vector field of 20 um.
std::string matrix_for(const fs::path& dir, const std::string& op) {
  auto r = run_process({cli_path().string(), "canon", "--decimals", "6", "--tool-table",
                        "tools.tbl", "--operation", op, "program.ngc"},
                       dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  std::string csv = "x,y,z,dx,dy,dz,valid,surface_id\n";
  static const std::regex call(R"((STRAIGHT_FEED|ARC_FEED)\((-?[0-9.]+), (-?[0-9.]+), )"
                               R"((-?[0-9.]+)(, (-?[0-9.]+), (-?[0-9]+), (-?[0-9.]+))?)");
  std::istringstream in(r.out);
  std::string line;
  int k = 0;
  std::smatch m;
  while (std::getline(in, line)) {
    if (!std::regex_search(line, m, call) || k++ % 4) continue;
    const bool arc = m[1] == "ARC_FEED";
    if (arc && !m[8].matched) continue;
    const double x = std::stod(m[2]), y = std::stod(m[3]), z = std::stod(arc ? m[8] : m[4]);
    char row[200];
    std::snprintf(row, sizeof row, "%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,1,1\n", x, y, z,
                  0.02 * std::sin(x / 7), 0.02 * std::cos(y / 5), 0.02 * std::sin(z / 3));
    csv += row;
  }
  return csv;
}

struct Op {
  std::string name, type;
  double radius_mm;
};

std::vector<Op> operations(const fs::path& dir) {
  const auto j = nlohmann::json::parse(read_file(dir / "part.json"));
  std::vector<Op> out;
  for (const auto& op : j["operations"]) {
    for (const auto& t : j["tools"]) {
      if (t["number"] != op["tool"]) continue;
      const double r = t["radius_mm"], cr = t["corner_radius_mm"];
      const std::string strategy = op["strategy"];
      const std::string type = cr > 0 && std::fabs(cr - r) < 1e-9           ? "ball"
                               : strategy.find("face") != std::string::npos ? "face"
                                                                            : "peripheral";
      out.push_back({op["name"], type, r});
    }
  }
  return out;
}

void check_part(const std::string& part) {
  const fs::path dir = scratch_dir() / part;
  auto made = run_process({cli_path().string(), "part", part, "--out", dir.string(), "--mesh-edge",
                           "2", "--stepover", "0.8", "--point-spacing", "1", "--step-down", "2"});
  if (made.exit_code != 0 && made.err.find("unknown part") != std::string::npos)
    GTEST_SKIP() << part << " is not a benchmark part of this build";
  ASSERT_EQ(made.exit_code, 0) << made.err;
  std::string why;
  const fs::path* oracle = rs274(why);
  if (!oracle) std::printf("rs274 not available (%s): truecut's interpreter only\n", why.c_str());
  write(dir / "tools-inch.tbl", inch_tools(read_file(dir / "tools.tbl")));

  const auto ops = operations(dir);
  ASSERT_FALSE(ops.empty());
  for (const Op& op : ops) {
    SCOPED_TRACE(part + " " + op.name);
    write(dir / (op.name + ".csv"), matrix_for(dir, op.name));
    const std::string out = op.name + ".ngc";
    char reach[32];
    std::snprintf(reach, sizeof reach, "%g", 2 * op.radius_mm + 1);
    auto r = run_process(
        {cli_path().string(), "rewrite", "program.ngc", "--matrix", op.name + ".csv", "--operation",
         op.name, "--type", op.type, "--tool-radius", std::to_string(op.radius_mm), "--reach",
         reach, "--tools", "tools.tbl", "--out", out},
        dir);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    std::printf("%s %s (%s): %s", part.c_str(), op.name.c_str(), op.type.c_str(),
                r.out.substr(r.out.find("  points written")).c_str());
    EXPECT_NE(r.out.find("points compensated"), std::string::npos);
    EXPECT_TRUE(read_file(dir / out) != read_file(dir / "program.ngc")) << "nothing rewritten";
    // truecut's interpreter.
    auto c = run_process({cli_path().string(), "canon", "--tool-table", "tools.tbl", out}, dir);
    EXPECT_EQ(c.exit_code, 0) << c.err;
    if (!oracle) continue;
    // rs274, and the same calls as truecut (without TRAORI/TRAFOOF for both).
    const std::string plain = op.name + "-plain.ngc";
    write(dir / plain, without_sinumerik(read_file(dir / out)));
    auto o = run_process({oracle->string(), "-g", "-t", "tools-inch.tbl", plain}, dir);
    EXPECT_EQ(o.exit_code, 0) << o.err.substr(0, 400);
    EXPECT_EQ(o.err.find("error"), std::string::npos) << o.err.substr(0, 400);
    auto t = run_process(
        {cli_path().string(), "canon", "--decimals", "8", "--tool-table", "tools.tbl", plain}, dir);
    ASSERT_EQ(t.exit_code, 0) << t.err;
    const auto expected = parse_listing(o.out), actual = parse_listing(t.out);
    EXPECT_GT(expected.size(), 100u);
    EXPECT_EQ(compare_listings(expected, actual), std::nullopt);
  }
}

TEST(RewriteParts, ImplantIsAcceptedByBothInterpreters) {
  check_part("implant");
}
TEST(RewriteParts, FreeformIsAcceptedByBothInterpreters) {
  check_part("freeform");
}
TEST(RewriteParts, Benchmark004IsAcceptedByBothInterpreters) {
  check_part("benchmark004");
}

}  // namespace
}  // namespace truecut::interp::testing
