// Interpreter and planner speed: blocks per second through the interpreter,
// planning speed, and the per-cycle cost of the interpolator.
//
//   interp_bench [--program FILE.ngc [--traori]] [--blocks N]
//
// Without --program a large program is generated: a 3-axis raster with arcs
// and a continuous 5-axis (TRAORI) part, N blocks in all (default 200000).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "truecut/interp/interpolator.hpp"
#include "truecut/interp/interpreter.hpp"
#include "truecut/interp/planner.hpp"

using namespace truecut::interp;
using Clock = std::chrono::steady_clock;

namespace {

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

std::string generated_program(int blocks) {
  std::ostringstream g;
  g.precision(4);
  g << std::fixed << "G21 G90 G17 G64 P0.01\nG0 X0 Y0 Z5 A0 C0\nG1 Z0 F2400\n";
  int n = 3;
  double y = 0;
  while (n < blocks / 2) {  // raster with arcs at the ends of the rows
    for (int i = 1; i <= 50; ++i, ++n)
      g << "X" << (i * 2.0) << " Y" << y + 0.01 * (i % 7) << "\n";
    g << "G3 X100 Y" << y + 1 << " R0.5\n";
    for (int i = 49; i >= 0; --i, ++n)
      g << "G1 X" << (i * 2.0) << " Y" << y + 1 + 0.01 * (i % 5) << "\n";
    g << "G2 X0 Y" << y + 2 << " R0.5\nG1\n";
    y += 2;
    n += 3;
  }
  g << "G0 Z20\nTRAORI\nG1 F1200\n";
  for (int i = 0; n < blocks; ++i, ++n)
    g << "X" << 40 * std::sin(i * 0.01) << " Y" << 40 * std::cos(i * 0.013) << " Z"
      << 10 + 5 * std::sin(i * 0.002) << " A" << 30 * std::sin(i * 0.003) << " C" << i * 0.05
      << "\n";
  g << "TRAFOOF\nM2\n";
  return g.str();
}

std::string read_program(const std::string& file, bool traori) {
  std::ifstream in(file);
  std::string text, line;
  static const std::regex remap(R"(^\s*[mM]4(28|29|30)\b.*)");
  while (std::getline(in, line)) {
    if (std::regex_match(line, remap)) {  // LinuxCNC's kinematics-switching remaps
      if (traori && line.find("428") != std::string::npos) text += "TRAORI\n";
      continue;
    }
    text += line + "\n";
  }
  return text;
}

}  // namespace

int main(int argc, char** argv) {
  std::string program_file;
  bool traori = false;
  int blocks = 200'000;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--program") && i + 1 < argc)
      program_file = argv[++i];
    else if (!std::strcmp(argv[i], "--traori"))
      traori = true;
    else if (!std::strcmp(argv[i], "--blocks") && i + 1 < argc)
      blocks = std::atoi(argv[++i]);
    else {
      std::fprintf(stderr, "usage: interp_bench [--program FILE.ngc [--traori]] [--blocks N]\n");
      return 2;
    }
  }
  const std::string text =
      program_file.empty() ? generated_program(blocks) : read_program(program_file, traori);
  const long lines = std::count(text.begin(), text.end(), '\n');
  std::printf("program: %s, %ld blocks, %.1f kB\n",
              program_file.empty() ? "generated" : program_file.c_str(), lines,
              text.size() / 1024.0);

  // Interpretation: best of 3 runs.
  CanonProgram canon;
  double interp_s = 1e300;
  for (int r = 0; r < 3; ++r) {
    const auto t0 = Clock::now();
    canon = Interpreter().run_text(text, "bench.ngc");
    interp_s = std::min(interp_s, seconds_since(t0));
  }
  std::printf("interpreter: %.3f s, %.0f blocks/s, %zu canonical calls\n", interp_s,
              lines / interp_s, canon.calls.size());

  PlannerOptions options;
  Plan plan;
  double plan_s = 1e300;
  for (int r = 0; r < 3; ++r) {
    const auto t0 = Clock::now();
    plan = plan_program(canon, options);
    plan_s = std::min(plan_s, seconds_since(t0));
  }
  std::printf(
      "planner: %.3f s, %.0f blocks/s, %zu plan segments (%.0f segments/s), %d blends, "
      "program time %.1f s\n",
      plan_s, lines / plan_s, plan.segments.size(), plan.segments.size() / plan_s,
      plan.stats.blends, plan.stats.duration_s);

  // Interpolator: every cycle of the plan, timed one by one.
  auto channel = std::make_unique<PlanChannel>();
  Interpolator ip;
  std::vector<double> cycle_ns;
  cycle_ns.reserve(static_cast<size_t>(plan.stats.duration_s / options.servo_period_s) + 16);
  size_t next = 0;
  while (!ip.output().done) {
    while (next < plan.segments.size() && channel->try_push(plan.segments[next]))
      ++next;
    const auto t0 = Clock::now();
    ip.step(*channel, options.servo_period_s);
    cycle_ns.push_back(std::chrono::duration<double, std::nano>(Clock::now() - t0).count());
  }
  std::vector<double> sorted = cycle_ns;
  std::sort(sorted.begin(), sorted.end());
  double sum = 0;
  for (double v : cycle_ns)
    sum += v;
  const double mean = sum / cycle_ns.size();
  const double p99 = sorted[sorted.size() * 99 / 100], worst = sorted.back();
  std::printf(
      "interpolator: %zu cycles, mean %.0f ns, p99 %.0f ns, max %.0f ns per cycle "
      "(mean %.4f %% of a 1 ms servo period)\n",
      cycle_ns.size(), mean, p99, worst, mean / 1e4);
  return 0;
}
