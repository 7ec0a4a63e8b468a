// `truecut rewrite` on every operation of the benchmark parts (implant,
// freeform, benchmark004), checked against what docs/rewrite.md claims:
// - the rewritten programs are accepted by truecut's interpreter and by
//   LinuxCNC's standalone rs274 (rs274_oracle.hpp), and both read them call
//   for call alike (TRAORI/TRAFOOF dropped for both);
// - every other line is copied: outside the operation the moves are the
//   original ones, exactly;
// - inside it every point is the original path's point shifted by the
//   correction, which never leaves the convex hull of the matrix's vectors
//   (Method, 5): each written point lies within the largest vector of the
//   matrix (plus the rounding of the written decimals, 0.1 µm by default in
//   G21) of the original path, A B C within the move's range; the G1 pieces
//   of an arc keep their chords within chord_tolerance_mm (0.001 mm,
//   Method, 3) of it, so each piece's midpoint lies within that plus the
//   largest vector;
// - the summary: the largest compensation is no larger than the largest
//   vector, the lines in and out are those of the two files.
// Without rs274 the truecut checks still run and the test is then skipped
// (or fails under TRUECUT_REQUIRE_ORACLES=1).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <regex>
#include <sstream>

#include "rs274_compare.hpp"
#include "rs274_oracle.hpp"
#include "run_process.hpp"
#include "test_paths.hpp"
#include "truecut/interp/interpreter.hpp"
#include "truecut/interp/rs274_format.hpp"

namespace truecut::interp::testing {
namespace {

namespace fs = std::filesystem;
using truecut::test::cli_path;
using truecut::test::read_file;
using truecut::test::run_process;
using truecut::test::scratch_dir;
using truecut::test::source_dir;

void write(const fs::path& p, const std::string& text) {
  std::ofstream(p, std::ios::binary) << text;
}

// What docs/rewrite.md states: G21 blocks are written with 4 decimals
// (--decimals, "0.1 µm"): each coordinate within half a unit of the last
// digit; arcs are cut into pieces whose chords stay within
// chord_tolerance_mm = 0.001 mm of the arc (Method, 3).
constexpr double kRoundingMm = 0.5e-4 * 1.7320508075688772;  // all three axes
constexpr double kRoundingDeg = 0.5e-4;
constexpr double kChordToleranceMm = 0.001;

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

// The largest compensation vector of a matrix written by matrix_for.
double largest_vector_mm(const std::string& csv) {
  std::istringstream in(csv);
  std::string line;
  std::getline(in, line);  // header
  double largest = 0;
  while (std::getline(in, line)) {
    double v[6];
    std::istringstream row(line);
    char comma;
    for (int i = 0; i < 6; ++i)
      row >> v[i] >> comma;
    largest = std::max(largest, std::sqrt(v[3] * v[3] + v[4] * v[4] + v[5] * v[5]));
  }
  return largest;
}

// One feed move of the original program, from `start`: a line or an arc
// (helical, radius changing linearly with the angle, as the planner and the
// rewrite take it).
struct Move {
  Axes6 start, end;
  bool arc = false;
  Axes6 center;
  int first = 0, second = 1, axis = 2;
  double r0 = 0, r1 = 0, a0 = 0, sweep = 0;

  Axes6 at(double t) const {
    Axes6 p;
    for (int i = 0; i < 6; ++i)
      p[i] = start[i] + t * (end[i] - start[i]);
    if (arc) {
      const double r = r0 + t * (r1 - r0), angle = a0 + t * sweep;
      p[first] = center[first] + r * std::cos(angle);
      p[second] = center[second] + r * std::sin(angle);
    }
    return p;
  }
};

double distance_xyz(const Axes6& p, const Axes6& q) {
  return std::sqrt((p.x - q.x) * (p.x - q.x) + (p.y - q.y) * (p.y - q.y) +
                   (p.z - q.z) * (p.z - q.z));
}

// Distance from q to the move's path in X Y Z, and the path parameter there.
double distance_to(const Move& m, const Axes6& q, double* at_t = nullptr) {
  double best_t = 0, best = distance_xyz(m.at(0), q);
  if (!m.arc) {
    double len2 = 0, dot = 0;
    for (int i = 0; i < 3; ++i) {
      len2 += (m.end[i] - m.start[i]) * (m.end[i] - m.start[i]);
      dot += (q[i] - m.start[i]) * (m.end[i] - m.start[i]);
    }
    best_t = len2 > 0 ? std::clamp(dot / len2, 0.0, 1.0) : 0.0;
    best = distance_xyz(m.at(best_t), q);
  } else {
    // Coarse samples, then a ternary search around the nearest one.
    const int n = 256;
    for (int k = 1; k <= n; ++k) {
      const double d = distance_xyz(m.at(double(k) / n), q);
      if (d < best) best = d, best_t = double(k) / n;
    }
    double lo = std::max(0.0, best_t - 1.0 / n), hi = std::min(1.0, best_t + 1.0 / n);
    for (int it = 0; it < 100; ++it) {
      const double t1 = lo + (hi - lo) / 3, t2 = hi - (hi - lo) / 3;
      if (distance_xyz(m.at(t1), q) < distance_xyz(m.at(t2), q))
        hi = t2;
      else
        lo = t1;
    }
    const double t = (lo + hi) / 2, d = distance_xyz(m.at(t), q);
    if (d < best) best = d, best_t = t;
  }
  if (at_t) *at_t = best_t;
  return best;
}

bool angles_within(const Move& m, const Axes6& q) {
  for (int i = 3; i < 6; ++i)
    if (q[i] < std::min(m.start[i], m.end[i]) - kRoundingDeg ||
        q[i] > std::max(m.start[i], m.end[i]) + kRoundingDeg)
      return false;
  return true;
}

Move line_move(const Axes6& start, const Axes6& end) {
  Move m;
  m.start = start;
  m.end = end;
  return m;
}

Move arc_move(const Axes6& start, const ArcFeed& a) {
  Move m;
  m.start = start;
  m.end = a.end;
  m.arc = true;
  m.center = a.center;
  if (a.plane == Plane::kXZ) m.first = 2, m.second = 0, m.axis = 1;
  if (a.plane == Plane::kYZ) m.first = 1, m.second = 2, m.axis = 0;
  const double s0 = start[m.first] - a.center[m.first], s1 = start[m.second] - a.center[m.second];
  const double e0 = a.end[m.first] - a.center[m.first], e1 = a.end[m.second] - a.center[m.second];
  m.r0 = std::hypot(s0, s1);
  m.r1 = std::hypot(e0, e1);
  m.a0 = std::atan2(s1, s0);
  double sweep = std::atan2(e1, e0) - m.a0;
  const double turn = 2 * std::numbers::pi;
  if (a.rotation > 0) {
    while (sweep <= 1e-12)
      sweep += turn;
    sweep += turn * (a.rotation - 1);
  } else {
    while (sweep >= -1e-12)
      sweep -= turn;
    sweep -= turn * (-a.rotation - 1);
  }
  m.sweep = sweep;
  return m;
}

struct Motion {
  std::vector<Move> feeds;         // the operation's feed moves, with their starts
  std::vector<Axes6> points;       // every motion end point, in order
  std::vector<int> point_kind;     // 0 traverse, 1 straight feed, 2 arc
  std::vector<bool> in_operation;  // the point's call belongs to the operation
  std::vector<std::string> other;  // motion calls outside the operation, as printed
};

Motion motion_of(const CanonProgram& program, const std::string& operation) {
  Motion out;
  Axes6 at;
  for (const auto& call : program.calls) {
    const bool in_op = call.context.operation == operation;
    const auto* traverse = std::get_if<StraightTraverse>(&call.op);
    const auto* feed = std::get_if<StraightFeed>(&call.op);
    const auto* arc = std::get_if<ArcFeed>(&call.op);
    if (!traverse && !feed && !arc) continue;
    const Axes6 end = traverse ? traverse->end : feed ? feed->end : arc->end;
    if (in_op && feed) out.feeds.push_back(line_move(at, end));
    if (in_op && arc) out.feeds.push_back(arc_move(at, *arc));
    if (!in_op) out.other.push_back(format_rs274(call.op, FormatOptions{9}));
    out.points.push_back(end);
    out.point_kind.push_back(traverse ? 0 : feed ? 1 : 2);
    out.in_operation.push_back(in_op);
    at = end;
  }
  return out;
}

// The rewritten operation's motion against the original's (header).
void expect_motion_within(const Motion& original, const Motion& rewritten, double largest_mm) {
  EXPECT_EQ(original.other, rewritten.other) << "moves outside the operation changed";
  ASSERT_FALSE(original.feeds.empty());
  const double point_tol = largest_mm + kRoundingMm + 1e-9;
  const double mid_tol = largest_mm + kChordToleranceMm + kRoundingMm + 1e-9;
  std::size_t j = 0, prev_j = 0;
  int checked = 0, failures = 0;
  for (std::size_t i = 0; i < rewritten.points.size() && failures < 5; ++i) {
    if (!rewritten.in_operation[i] || rewritten.point_kind[i] == 0) continue;
    const Axes6& p = rewritten.points[i];
    // The first original move at or after the previous point's that holds it.
    std::size_t k = j;
    while (k < original.feeds.size() &&
           !(distance_to(original.feeds[k], p) <= point_tol && angles_within(original.feeds[k], p)))
      ++k;
    if (k == original.feeds.size()) {
      double nearest = 1e300;
      for (std::size_t m = j; m < std::min(original.feeds.size(), j + 3); ++m)
        nearest = std::min(nearest, distance_to(original.feeds[m], p));
      ADD_FAILURE() << "written point " << format_rs274(StraightFeed{p}, FormatOptions{6}) << " is "
                    << nearest << " mm from the original path (moves " << j << "..)"
                    << ", more than the largest compensation vector " << largest_mm
                    << " mm plus rounding";
      ++failures;
      continue;
    }
    prev_j = j;
    j = k;
    ++checked;
    // A straight piece's midpoint: within the chord tolerance of the path
    // (of the move it ends on, or the one its start belongs to).
    if (rewritten.point_kind[i] != 1 || i == 0) continue;
    Axes6 mid;
    for (int a = 0; a < 6; ++a)
      mid[a] = (rewritten.points[i - 1][a] + p[a]) / 2;
    double d = 1e300;
    for (std::size_t m = prev_j; m <= std::min(k + 1, original.feeds.size() - 1); ++m)
      d = std::min(d, distance_to(original.feeds[m], mid));
    if (d > mid_tol) {
      ADD_FAILURE() << "the piece ending at " << format_rs274(StraightFeed{p}, FormatOptions{6})
                    << " has its midpoint " << d << " mm from the original path, more than "
                    << mid_tol << " mm (largest vector + chord tolerance + rounding)";
      ++failures;
    }
  }
  EXPECT_EQ(failures, 0);
  EXPECT_GE(checked, static_cast<int>(original.feeds.size())) << "points of the operation";
}

int lines_in(const std::string& text) {
  return static_cast<int>(std::count(text.begin(), text.end(), '\n')) +
         (!text.empty() && text.back() != '\n');
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
  ASSERT_EQ(made.exit_code, 0) << made.err;
  std::string why;
  const auto& rs274 = rs274_oracle(why);
  const fs::path* oracle = rs274 ? &rs274->program : nullptr;
  write(dir / "tools-inch.tbl", inch_tools(read_file(dir / "tools.tbl")));
  InterpreterOptions io;
  io.tools = ToolTable::load(dir / "tools.tbl");
  const Interpreter interpreter(io);
  const CanonProgram original = interpreter.run_file(dir / "program.ngc");

  const auto ops = operations(dir);
  ASSERT_FALSE(ops.empty());
  for (const Op& op : ops) {
    SCOPED_TRACE(part + " " + op.name);
    const std::string matrix = matrix_for(dir, op.name);
    write(dir / (op.name + ".csv"), matrix);
    const double largest = largest_vector_mm(matrix);
    ASSERT_GT(largest, 0.0);
    const std::string out = op.name + ".ngc";
    char reach[32];
    std::snprintf(reach, sizeof reach, "%g", 2 * op.radius_mm + 1);
    // The radius comes from tools.tbl; --tool-radius (part.json's) is the
    // check that both agree.
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
    // The summary (the audit record holds it unrounded).
    const auto summary =
        nlohmann::json::parse(read_file(dir / (out + ".audit.json"))).at("summary");
    EXPECT_GT(summary.at("moves_rewritten").get<int>(), 0);
    EXPECT_GT(summary.at("points_compensated").get<int>(), 0);
    EXPECT_LE(summary.at("points_compensated").get<int>(), summary.at("points_written").get<int>());
    EXPECT_LE(summary.at("max_compensation_mm").get<double>(), largest * (1 + 1e-12))
        << "a correction outside the convex hull of the matrix's vectors";
    EXPECT_LE(summary.at("mean_compensation_mm").get<double>(),
              summary.at("max_compensation_mm").get<double>() * (1 + 1e-12));  // summation
    EXPECT_EQ(summary.at("lines_in").get<int>(), lines_in(read_file(dir / "program.ngc")));
    EXPECT_EQ(summary.at("lines_out").get<int>(), lines_in(read_file(dir / out)));
    // truecut's interpreter.
    auto c = run_process({cli_path().string(), "canon", "--tool-table", "tools.tbl", out}, dir);
    EXPECT_EQ(c.exit_code, 0) << c.err;
    // The motion: the original path shifted by at most the largest vector.
    expect_motion_within(motion_of(original, op.name),
                         motion_of(interpreter.run_file(dir / out), op.name), largest);
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
  if (!oracle) TRUECUT_ORACLE_MISSING(rs274_missing(why));
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
