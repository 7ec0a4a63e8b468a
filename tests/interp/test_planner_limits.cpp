// Velocity, acceleration and jerk of every joint stay within the machine
// limits on every servo cycle, measured on the sampled setpoints by finite
// differences, for the corpus, LinuxCNC's 5-axis samples and generated
// programs.
#include <random>

#include "planner_test_util.hpp"

namespace truecut::interp::testing {
namespace {

namespace fs = std::filesystem;

void expect_within_limits(const CanonProgram& program, const PlannerOptions& o,
                          const std::string& what) {
  const Plan plan = plan_program(program, o);
  const auto s = sample_plan(plan, o.servo_period_s);
  ASSERT_TRUE(s.back().done) << what;
  const LimitCheck c = check_limits(s, o.limits, o.servo_period_s);
  EXPECT_TRUE(c.ok()) << what << ": " << c.describe(s);
}

TEST(PlannerLimits, OwnCorpus) {
  int n = 0;
  for (const auto& e :
       fs::directory_iterator(truecut::test::source_dir() / "tests/interp/corpus")) {
    if (e.path().extension() != ".ngc") continue;
    InterpreterOptions io;
    io.tools = sample_tools();
    io.tools = ToolTable::parse("T1 P1 D6 Z10\nT2 P2 D3 Z20\nT3 P3 D4 Z5\nT7 P9 D10 Z-5\n", "t");
    CanonProgram program;
    try {
      program = Interpreter(io).run_file(e.path());
    } catch (const GcodeError&) {
      continue;  // corpus files that need another tool table
    }
    expect_within_limits(program, PlannerOptions{}, e.path().filename().string());
    ++n;
  }
  EXPECT_GE(n, 5);
}

TEST(PlannerLimits, LinuxCncFiveAxisDemos) {
  std::string why;
  const auto share = linuxcnc_share(why);
  if (!share) TRUECUT_ORACLE_MISSING(rs274_missing(why));
  for (const char* name : {"boat-xyzac.ngc", "impeller-7bl-xyzac.ngc"})
    for (bool tcp : {false, true}) {
      const CanonProgram program = run(demo_text(five_axis_demo(*share, name), tcp));
      PlannerOptions o;
      if (tcp) {  // a table with real pivots, so TCP and joints differ
        o.kinematics.y_rot_point_mm = 5;
        o.kinematics.z_offset_mm = 20;
      }
      expect_within_limits(program, o, std::string(name) + (tcp ? " (TRAORI)" : ""));
    }
}

// Random polylines and arcs on a slow, stiff-jerk machine and a fast one.
std::string random_program(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> pos(-20, 20), rot(-30, 30), len(0.02, 3);
  std::ostringstream g;
  g << "G21 G90 G17 G64 P0.02\nG0 X0 Y0 Z0\nF" << 600 + (seed % 5) * 1000 << "\n";
  double x = 0, y = 0;
  for (int i = 0; i < 300; ++i) {
    const int kind = rng() % 10;
    if (kind < 6) {
      const double a = pos(rng) * 0.3, l = len(rng);
      x += l * std::cos(a), y += l * std::sin(a);
      g << "G1 X" << x << " Y" << y << " Z" << pos(rng) * 0.01;
      if (kind == 0) g << " A" << rot(rng) << " C" << rot(rng) * 4;
      g << "\n";
    } else if (kind < 8) {
      const double r = len(rng) + 0.5;
      g << (kind == 6 ? "G2" : "G3") << " X" << x + 2 * r << " Y" << y << " I" << r << " J0\n";
      x += 2 * r;
    } else if (kind == 8) {
      g << "G61\nG1 X" << x << " Y" << y + 1 << "\nG64 P" << 0.001 * (1 + rng() % 50) << "\n";
      y += 1;
    } else {
      g << "G0 Z5\nG0 X" << x << " Y" << y << "\nG1 Z0\n";
    }
  }
  g << "M2\n";
  return g.str();
}

TEST(PlannerLimits, RandomPrograms) {
  PlannerOptions slow;
  for (auto& a : slow.limits.axis)
    a = {a.max_velocity * 0.3, a.max_acceleration * 0.2, a.max_jerk * 0.05};
  PlannerOptions fast;
  for (auto& a : fast.limits.axis)
    a = {a.max_velocity * 3, a.max_acceleration * 5, a.max_jerk * 10};
  for (unsigned seed = 1; seed <= 6; ++seed) {
    const CanonProgram p = run(random_program(seed));
    expect_within_limits(p, slow, "slow machine, seed " + std::to_string(seed));
    expect_within_limits(p, fast, "fast machine, seed " + std::to_string(seed));
  }
}

TEST(PlannerLimits, CheckerCatchesAViolation) {
  // A plan made for a fast machine violates a slow machine's limits: the
  // finite-difference check must say so.
  PlannerOptions fast, slow;
  for (auto& a : fast.limits.axis)
    a = {a.max_velocity * 3, a.max_acceleration * 5, a.max_jerk * 10};
  const Plan plan = plan_program(run("G1 X50 Y20 F6000\nX0\nM2\n"), fast);
  const auto s = sample_plan(plan, fast.servo_period_s);
  EXPECT_TRUE(check_limits(s, fast.limits, fast.servo_period_s).ok());
  EXPECT_FALSE(check_limits(s, slow.limits, slow.servo_period_s).ok());
}

TEST(PlannerLimits, EndsAtTheProgrammedPosition) {
  const auto s = sample_plan(plan_text("G0 X3 Y4 Z5\nG1 X10 A30 C-45 F900\nM2\n"), 0.001);
  ASSERT_TRUE(s.back().done);
  const std::array<double, 5> want{10, 4, 5, 30, -45};
  for (int j = 0; j < 5; ++j)
    EXPECT_NEAR(want[j], s.back().joints[j], 1e-9) << j;
}

TEST(PlannerLimits, RejectsNonPositiveLimits) {
  PlannerOptions o;
  o.limits.axis[kAxisC].max_jerk = 0;
  EXPECT_THROW(plan_text("G1 X1 F100\nM2\n", o), std::invalid_argument);
}

}  // namespace
}  // namespace truecut::interp::testing
