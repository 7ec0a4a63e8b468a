// Checks shared by the benchmark-part tests: the program through truecut's
// interpreter with the part's tool table, feed-move end points, the tool
// axis of A/C, and mesh closure.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Core>

#include <cmath>
#include <map>
#include <numbers>
#include <utility>
#include <variant>

#include "truecut/interp/interpreter.hpp"
#include "truecut/offline/mesh.hpp"
#include "truecut/sim/benchmark_parts.hpp"

namespace truecut::sim::test {

inline interp::CanonProgram interpret(const BenchmarkPart& part) {
  interp::InterpreterOptions o;
  o.tools = interp::ToolTable::parse(tool_table_text(part.metadata), "tools.tbl");
  return interp::Interpreter(o).run_text(part.program, "program.ngc");
}

inline const interp::Axes6* feed_end(const interp::CanonCall& c) {
  if (const auto* f = std::get_if<interp::StraightFeed>(&c.op)) return &f->end;
  if (const auto* a = std::get_if<interp::ArcFeed>(&c.op)) return &a->end;
  return nullptr;
}

// docs/kinematics.md, σ = +1.
inline Eigen::Vector3d tool_axis(double a_deg, double c_deg) {
  const double a = a_deg * std::numbers::pi / 180, c = c_deg * std::numbers::pi / 180;
  return {std::sin(a) * std::sin(c), std::sin(a) * std::cos(c), std::cos(a)};
}

// Every undirected edge in exactly two triangles, every directed edge once
// (neighbours traverse their shared edge in opposite directions).
inline void expect_closed_and_consistent(const offline::TriangleMesh& mesh) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
  for (const auto& t : mesh.triangles) {
    ASSERT_TRUE(t[0] != t[1] && t[1] != t[2] && t[0] != t[2]);
    for (int k = 0; k < 3; ++k)
      ++directed[{t[k], t[(k + 1) % 3]}];
  }
  int bad = 0;
  for (const auto& [edge, count] : directed) {
    const auto back = directed.find({edge.second, edge.first});
    if (count != 1 || back == directed.end() || back->second != 1) ++bad;
  }
  EXPECT_EQ(bad, 0) << "edges not shared by exactly two consistently oriented triangles";
}

}  // namespace truecut::sim::test
