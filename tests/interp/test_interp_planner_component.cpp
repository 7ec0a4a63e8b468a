// The interp_planner HAL component: loads a program, runs it in the servo
// thread, reports the pose on its pins and stops the executor at the end.
#include "planner_test_util.hpp"
#include "truecut/rt/executor.hpp"
#include "truecut/rt/hal_file.hpp"

namespace truecut::interp::testing {
namespace {

rt::hal::HalOptions options(const std::filesystem::path& dir) {
  rt::hal::HalOptions o;
  o.component_path = {truecut::test::component_dir()};
  o.output_dir = dir;
  return o;
}

TEST(InterpPlannerComponent, RunsTheProgramAndStops) {
  const auto dir = truecut::test::scratch_dir();
  std::ofstream(dir / "p.ngc") << "(OPERATION: FACE)\nG0 X0 Y0 Z5\nG1 Z0 F600\nG1 X10 Y4\nM2\n";
  rt::hal::Hal h(options(dir));
  rt::hal::load_hal_text(h,
                         "loadrt threads name1=servo-thread period1=1000000\n"
                         "loadrt interp_planner names=ip program=" +
                             (dir / "p.ngc").string() +
                             " vmax=100,100,100,90,180\n"
                             "loadrt recorder file=trace.csv columns=x,y,line:s32\n"
                             "net x ip.joint-x => recorder.0.x\n"
                             "net y ip.tcp-y => recorder.0.y\n"
                             "net line ip.line => recorder.0.line\n"
                             "addf ip.update servo-thread\naddf recorder.0.sample servo-thread\n",
                         "p.hal");
  rt::hal::Executor ex(h);
  rt::hal::RunLimits lim;
  lim.max_cycles = 100'000;
  const auto r = ex.run_simulated(lim);
  EXPECT_TRUE(r.stopped_by_request);
  EXPECT_LT(r.threads[0].cycles, 100'000u);
  EXPECT_TRUE(h.get_pin_or_param("ip.done").b);
  EXPECT_FALSE(h.get_pin_or_param("ip.underrun").b);
  EXPECT_NEAR(10.0, h.get_pin_or_param("ip.joint-x").f, 1e-9);
  EXPECT_NEAR(4.0, h.get_pin_or_param("ip.tcp-y").f, 1e-9);
  EXPECT_NEAR(1.0, h.get_pin_or_param("ip.axis-k").f, 1e-12);
  EXPECT_EQ(1, h.get_pin_or_param("ip.operation").s);
  EXPECT_EQ(4, h.get_pin_or_param("ip.line").s);
  // The same setpoints as the planner and interpolator called directly.
  const auto s = sample_plan(plan_program(Interpreter().run_file(dir / "p.ngc"),
                                          [] {
                                            PlannerOptions o;
                                            for (int i = 0; i < 3; ++i)
                                              o.limits.axis[i].max_velocity = 100;
                                            return o;
                                          }()),
                             0.001);
  EXPECT_EQ(s.size(), r.threads[0].cycles);
}

TEST(InterpPlannerComponent, BadProgramFailsTheLoadWithItsLocation) {
  const auto dir = truecut::test::scratch_dir();
  std::ofstream(dir / "bad.ngc") << "G1 X10 F100\nG2 X5\nM2\n";
  rt::hal::Hal h(options(dir));
  try {
    rt::hal::load_hal_text(h, "loadrt interp_planner program=" + (dir / "bad.ngc").string() + "\n",
                           "p.hal");
    FAIL() << "the load should fail";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("bad.ngc:2:"), std::string::npos) << e.what();
  }
}

TEST(InterpPlannerComponent, RejectsBadLimits) {
  const auto dir = truecut::test::scratch_dir();
  std::ofstream(dir / "p.ngc") << "G1 X1 F100\nM2\n";
  rt::hal::Hal h(options(dir));
  EXPECT_ANY_THROW(rt::hal::load_hal_text(
      h, "loadrt interp_planner program=" + (dir / "p.ngc").string() + " vmax=1,2,3\n", "p.hal"));
}

}  // namespace
}  // namespace truecut::interp::testing
