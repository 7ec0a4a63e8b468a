// The program travel check: every benchmark part's program stays inside the
// travel of the machine it is written with (machine.json, read back), and
// programs that leave a joint's travel — at a line end, in the middle of an
// arc, through G43, under TRAORI, on a joint the machine lacks — are
// reported at the right line with the joint and position.
#include <gtest/gtest.h>

#include <cmath>

#include "part_test_support.hpp"
#include "test_paths.hpp"
#include "truecut/sim/benchmark_parts.hpp"
#include "truecut/sim/program_travel.hpp"

using namespace truecut::sim;

namespace {

PartOptions coarse() {
  return {2.0, 0.8, 1.0, 2.0};
}

MachineParams demo_machine() {
  return part_machine(make_part(PartId::kImplant, coarse())).machine;
}

ProgramTravel travel_of(const std::string& text, const MachineParams& m,
                        const std::string& tools = "T1 P1 D10.000 Z60.000 ;\n") {
  truecut::interp::InterpreterOptions o;
  o.tools = truecut::interp::ToolTable::parse(tools, "tools.tbl");
  return program_travel(truecut::interp::Interpreter(o).run_text(text, "program.ngc"), m,
                        "program.ngc");
}

}  // namespace

TEST(ProgramTravel, EveryPartStaysInsideTheTravelOfItsMachineJson) {
  for (PartId id : kAllParts) {
    const BenchmarkPart part = make_part(id, coarse());
    const auto dir = truecut::test::scratch_dir() / std::string(part_name(id));
    write_part(part, dir);
    for (const char* file : {"machine.json", "machine_ideal.json"}) {
      const MachineDescription d = read_machine_description(dir / file);
      EXPECT_EQ(
          d, std::string(file) == "machine.json" ? part_machine(part) : part_machine_ideal(part));
      const ProgramTravel t =
          program_travel(truecut::sim::test::interpret(part), d.machine, "program.ngc");
      EXPECT_TRUE(t.inside()) << part_name(id) << ": " << t.first_excursion->message;
      EXPECT_GT(t.samples, 100u);
      // With margin: at least 20 mm (linear) / 5° (A) from every end.
      for (int j = 0; j < 4; ++j) {
        const double margin = j < 3 ? 20.0 : 5.0;
        EXPECT_GE(t.min[j], d.machine.joints[j].min + margin) << part_name(id) << " joint " << j;
        EXPECT_LE(t.max[j], d.machine.joints[j].max - margin) << part_name(id) << " joint " << j;
      }
      // The program's own A range is the part's.
      EXPECT_GE(t.min[kA], part.metadata.a_min_deg - 1e-9) << part_name(id);
      EXPECT_LE(t.max[kA], part.metadata.a_max_deg + 1e-9) << part_name(id);
    }
  }
}

TEST(ProgramTravel, HiddenPhysicsIsOnInMachineJsonAndOffInTheIdealOne) {
  for (PartId id : kAllParts) {
    const BenchmarkPart part = make_part(id, coarse());
    const MachineDescription real = part_machine(part), ideal = part_machine_ideal(part);
    EXPECT_EQ(real.machine.joints, ideal.machine.joints);
    EXPECT_EQ(real.machine.kinematics, ideal.machine.kinematics);
    EXPECT_EQ(ideal.machine.effects, Effects{});
    EXPECT_TRUE(real.machine.effects.servo_lag.enabled);
    for (int j = 0; j < kJointCount; ++j)
      EXPECT_TRUE(real.machine.effects.servo_lag.active(j)) << j;
    EXPECT_TRUE(real.machine.effects.tool_radius_error.enabled);
    EXPECT_LT(real.machine.effects.tool_radius_error.params.radius_mm, 0);
    EXPECT_GE(real.machine.effects.tool_radius_error.params.radius_mm, -0.1);
    EXPECT_EQ(real.machine.effects.rotary_location.enabled, id == PartId::kFreeform);
    EXPECT_GT(real.machine.kinematics.tool.radius_mm, 0);
  }
}

TEST(ProgramTravel, ReportsTheFirstLineThatLeavesZ) {
  const ProgramTravel t =
      travel_of("G21 G90 G61\nG0 X10 Y0 Z100\nG0 Z400\nG0 Z500\nM2\n", demo_machine());
  ASSERT_FALSE(t.inside());
  EXPECT_EQ(t.first_excursion->line, 3);
  EXPECT_EQ(t.first_excursion->joint, kZ);
  EXPECT_DOUBLE_EQ(t.first_excursion->position, 400.0);
  EXPECT_EQ(t.first_excursion->message,
            "program.ngc:3: joint Z leaves travel [-50, 350] at 400 mm");
  EXPECT_DOUBLE_EQ(t.max[kZ], 500.0);  // the extent covers the whole program
}

TEST(ProgramTravel, ToolLengthOffsetCounts) {
  const std::string program = "G21 G90\nT1 M6\nG43 H1\nG0 X0 Y0 Z300\nM2\n";
  EXPECT_TRUE(travel_of(program, demo_machine(), "T1 P1 D10.000 Z40.000 ;\n").inside());
  const ProgramTravel t = travel_of(program, demo_machine(), "T1 P1 D10.000 Z60.000 ;\n");
  ASSERT_FALSE(t.inside());
  EXPECT_EQ(t.first_excursion->line, 4);
  EXPECT_NEAR(t.first_excursion->position, 360.0, 1e-9);
}

// A LinuxCNC spline (G5.1, docs/gcode.md "Splines G5.x") is planned as
// chords of its curve: from (240, -100) to (240, 100) with its control
// point at (280, 0) it reaches x = 260 > 250 half way, the ends inside.
TEST(ProgramTravel, FindsASplineThatBulgesOutBetweenEndsInside) {
  const ProgramTravel t =
      travel_of("G21 G90 G17\nG0 X240 Y-100 Z50\nG5.1 I40 J100 X240 Y100 F1000\nG0 X200\nM2\n",
                demo_machine());
  ASSERT_FALSE(t.inside());
  EXPECT_EQ(t.first_excursion->line, 3);
  EXPECT_EQ(t.first_excursion->joint, kX);
  EXPECT_GT(t.first_excursion->position, 250.0);
  EXPECT_NEAR(t.max[kX], 260.0, 0.03);  // within the planner's 0.025 mm chords
}

TEST(ProgramTravel, FindsAnArcThatBulgesOutBetweenEndsInside) {
  // Counter-clockwise about the origin from (240, −100) to (240, 100):
  // radius 260, through x = 260 > 250 at mid-arc.
  const ProgramTravel t = travel_of(
      "G21 G90 G17\nG0 X240 Y-100 Z50\nG3 X240 Y100 I-240 J100 F1000\nM2\n", demo_machine());
  ASSERT_FALSE(t.inside());
  EXPECT_EQ(t.first_excursion->line, 3);
  EXPECT_EQ(t.first_excursion->joint, kX);
  EXPECT_GT(t.first_excursion->position, 250.0);
  EXPECT_NEAR(t.max[kX], 260.0, 0.05);
}

TEST(ProgramTravel, TcpMovesAreCheckedInJoints) {
  // Under TRAORI a tool axis of 120° needs A = 120°, beyond the trunnion
  // (the 150 mm tool keeps Z inside while the table tilts).
  const ProgramTravel t =
      travel_of("G21 G90\nT1 M6\nG43 H1\nTRAORI\nG0 X0 Y0 Z50 A0 C0\nG1 A60 F1000\nG1 A120\nM2\n",
                demo_machine(), "T1 P1 D10.000 Z150.000 ;\n");
  ASSERT_FALSE(t.inside()) << t.max[kA];
  EXPECT_EQ(t.first_excursion->line, 7);
  EXPECT_EQ(t.first_excursion->joint, kA);
  EXPECT_GT(t.first_excursion->position, 110.0);
  EXPECT_LE(t.first_excursion->position, 110.0 + 0.6);  // sampled every 0.5 mm (w = 1 mm/deg)
  EXPECT_EQ(
      t.first_excursion->message.rfind("program.ngc:7: joint A leaves travel [-10, 110] at ", 0),
      0u)
      << t.first_excursion->message;
  // The trunnion (A axis 100 mm below the workpiece origin) swings the TCP
  // at z = 50 to Y = −150 sin A in the machine.
  EXPECT_NEAR(t.min[kY], -150.0, 1e-3);
}

TEST(ProgramTravel, AJointTheMachineLacksHasNoTravel) {
  MachineParams three_axis = demo_machine();
  three_axis.joints[kA] = {};
  three_axis.joints[kC] = {};
  EXPECT_TRUE(travel_of("G21 G90\nG0 X10 Y10 Z10\nM2\n", three_axis).inside());
  // G61: without it the G64 blend into line 3 already turns A in line 2.
  const ProgramTravel t = travel_of("G21 G90 G61\nG0 X10 Y10 Z10\nG0 A5\nM2\n", three_axis);
  ASSERT_FALSE(t.inside());
  EXPECT_EQ(t.first_excursion->message, "program.ngc:3: joint A leaves travel [0, 0] at 5 deg");
}
