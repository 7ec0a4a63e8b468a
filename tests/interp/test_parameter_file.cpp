// interp::ParameterFile (LinuxCNC's .var file) and the interpreter's start
// from it: the rules rs274 2.9 applies (order, range, skipped lines), the
// lines truecut refuses where rs274 silently drops them, and the setup the
// program starts in (active system, its rotation, G92, units).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "test_paths.hpp"
#include "truecut/interp/error.hpp"
#include "truecut/interp/interpreter.hpp"
#include "truecut/interp/parameter_file.hpp"

namespace truecut::interp {
namespace {

std::string error_of(const std::string& text) {
  try {
    ParameterFile::parse(text, "m.var");
  } catch (const GcodeError& e) {
    return e.what();
  }
  return "no error";
}

TEST(ParameterFile, ReadsLinuxCncLinesSkipsCommentsAndTrailingWords) {
  const ParameterFile f = ParameterFile::parse(
      "# written by hand\n\n5161\t1.5\n  5220 2.000000\n5241 -3e1 the X offset of G55\n"
      "5250 30\r\n",
      "m.var");
  ASSERT_EQ(f.values.size(), 4u);
  EXPECT_EQ(f.values.at(5161), 1.5);
  EXPECT_EQ(f.values.at(5220), 2.0);
  EXPECT_EQ(f.values.at(5241), -30.0);
  EXPECT_EQ(f.values.at(5250), 30.0);
  EXPECT_EQ(ParameterFile::parse("", "empty.var").values.size(), 0u);
}

TEST(ParameterFile, RefusesWhatLinuxCncRefusesAndWhatItWouldSilentlyDrop) {
  // LinuxCNC: "Parameter file out of order", "Parameter number out of range".
  EXPECT_EQ(error_of("5221 1\n5220 1\n"),
            "m.var:2:1: parameter 5220 after 5221 (line 1): the numbers must rise from line to "
            "line, as LinuxCNC requires (\"Parameter file out of order\")");
  EXPECT_EQ(error_of("5221 1\n5221 2\n").substr(0, 37), "m.var:2:1: parameter 5221 after 5221 ");
  EXPECT_EQ(error_of("0 5\n"), "m.var:1:1: parameter number 0 out of range 1..5601");
  EXPECT_EQ(error_of("5602 1\n"), "m.var:1:1: parameter number 5602 out of range 1..5601");
  EXPECT_EQ(error_of("-5 1\n"), "m.var:1:1: parameter number -5 out of range 1..5601");
  EXPECT_EQ(error_of("99999999999 1\n"),
            "m.var:1:1: parameter number 99999999999 out of range 1..5601");
  EXPECT_EQ(error_of("5601 1\n"), "no error");
  EXPECT_EQ(error_of("+5221 1\n"), "no error");  // as sscanf("%d") reads it
  // rs274 skips these lines or reads "5221.5 3" as #5221 = 0.5.
  EXPECT_EQ(error_of("5221\n"), "m.var:1:1: parameter 5221 has no value");
  EXPECT_EQ(error_of("5221 abc\n"), "m.var:1:6: parameter 5221: 'abc' is not a finite number");
  EXPECT_EQ(error_of("5221 nan\n"), "m.var:1:6: parameter 5221: 'nan' is not a finite number");
  EXPECT_EQ(error_of("5221 1e999\n"), "m.var:1:6: parameter 5221: '1e999' is not a finite number");
  EXPECT_EQ(error_of("5221.5 3\n"),
            "m.var:1:1: parameter number '5221....' is not a whole number followed by white "
            "space");
  // rs274 falls back to G54 (12) or truncates (2.5).
  EXPECT_EQ(error_of("5220 12\n"),
            "m.var:1:6: parameter 5220 (the active coordinate system) must be 1..9 (G54..G59.3), "
            "got 12");
  EXPECT_EQ(error_of("5220 2.5\n"),
            "m.var:1:6: parameter 5220 (the active coordinate system) must be 1..9 (G54..G59.3), "
            "got 2.5");
  EXPECT_THROW(ParameterFile::load(truecut::test::scratch_dir() / "missing.var"), GcodeError);
}

// Offsets and stored positions beyond any machine (a unit or typing
// mistake): refused at their line, instead of a misleading program error
// later (a 1e300 mm G54 X made the program's first arc "zero-radius").
// A byte-order mark would make LinuxCNC skip the first line and its value.
TEST(ParameterFile, OffsetsBeyondAnyMachineAndAByteOrderMarkAreRefused) {
  EXPECT_EQ(error_of("5221 1e300\n"),
            "m.var:1:6: parameter 5221: 1e300 mm is outside the offsets a machine can have "
            "(±1e5 mm: no machine is larger than 100 m)");
  EXPECT_NE(error_of("5211 -200000\n").find("parameter 5211: -200000 mm is outside"),
            std::string::npos);  // G92 X
  EXPECT_NE(error_of("5181 1e6\n").find("parameter 5181: 1e6 mm is outside"),
            std::string::npos);      // G30 X
  EXPECT_EQ(error_of("5390 2e6\n"),  // G59.3 R
            "m.var:1:6: parameter 5390: 2e6 deg is outside the offsets a machine can have "
            "(±1e6 deg: no machine is larger than 100 m)");
  EXPECT_NE(error_of("5224 -1e7\n"), "no error");  // G54 A
  // The largest plausible ones, and parameters that are no offsets, pass.
  EXPECT_EQ(error_of("5221 -100000\n5224 3600\n5230 -45\n"), "no error");
  EXPECT_EQ(error_of("100 1e300\n"), "no error");
  try {
    ParameterFile::parse("5221 4000\n", "i.var", LengthUnits::kInch);
    ADD_FAILURE() << "4000 inch is over 100 m";
  } catch (const GcodeError& e) {
    EXPECT_NE(std::string(e.what()).find("4000 inch is outside"), std::string::npos) << e.what();
  }
  EXPECT_EQ(error_of("\xEF\xBB\xBF"
                     "5221 10\n"),
            "m.var:1:1: the file starts with a UTF-8 byte-order mark: LinuxCNC would skip its "
            "first line and the value on it; save the file without it");
}

// The first SET_G5X_OFFSET, SET_G92_OFFSET and SET_XY_ROTATION of a program
// started from `f`, and the machine position of its first move.
struct Start {
  SetG5xOffset g5x;
  SetG92Offset g92;
  double rotation_deg = 0;
  Axes6 machine_mm;
};

Start start_of(const ParameterFile& f, const std::string& program) {
  InterpreterOptions o;
  o.parameters = f;
  const CanonProgram p = Interpreter(o).run_text(program, "p.ngc");
  Start s;
  bool g5x = false, g92 = false, rot = false, move = false;
  for (const CanonCall& c : p.calls) {
    if (const auto* x = std::get_if<SetG5xOffset>(&c.op); x && !g5x) s.g5x = *x, g5x = true;
    if (const auto* x = std::get_if<SetG92Offset>(&c.op); x && !g92) s.g92 = *x, g92 = true;
    if (const auto* x = std::get_if<SetXYRotation>(&c.op); x && !rot)
      s.rotation_deg = x->degrees, rot = true;
    if (const auto* m = std::get_if<StraightTraverse>(&c.op); m && !move) {
      s.machine_mm = machine_position_mm(m->end, c.context);
      move = true;
    }
  }
  EXPECT_TRUE(g5x && g92 && rot && move);
  return s;
}

TEST(ParameterFile, TheProgramStartsInTheSetupTheFileHolds) {
  const std::string text =
      "5210 1\n5211 0.5\n5212 -0.25\n5213 1\n5220 2\n5241 10\n5242 20\n5243 -30\n5244 15\n"
      "5250 90\n";
  const std::string program = "G21 G90\nG0 X1 Y2 Z3\nM2\n";
  // In mm: G55 active, turned 90 degrees, G92 on.
  const Start mm = start_of(ParameterFile::parse(text, "m.var"), program);
  EXPECT_EQ(mm.g5x.index, 2);
  EXPECT_EQ(mm.g5x.offset.x, 10.0);
  EXPECT_EQ(mm.g5x.offset.z, -30.0);
  EXPECT_EQ(mm.g5x.offset.a, 15.0);
  EXPECT_EQ(mm.g92.offset.x, 0.5);
  EXPECT_EQ(mm.rotation_deg, 90.0);
  // machine = G55 + rotation x (program + G92): (1.5, 1.75) turned by 90°.
  EXPECT_NEAR(mm.machine_mm.x, 10.0 - 1.75, 1e-12);
  EXPECT_NEAR(mm.machine_mm.y, 20.0 + 1.5, 1e-12);
  EXPECT_NEAR(mm.machine_mm.z, -30.0 + 3.0 + 1.0, 1e-12);
  EXPECT_NEAR(mm.machine_mm.a, 0.0, 1e-12);  // A is not moved: it stays where it was
  // In inches: lengths x 25.4, angles and the A offset as written.
  const Start inch = start_of(ParameterFile::parse(text, "i.var", LengthUnits::kInch), program);
  EXPECT_NEAR(inch.g5x.offset.x, 254.0, 1e-12);
  EXPECT_NEAR(inch.g92.offset.y, -6.35, 1e-12);
  EXPECT_EQ(inch.g5x.offset.a, 15.0);
  EXPECT_EQ(inch.rotation_deg, 90.0);
  // G92 offsets are applied only when #5210 is 1, as in rs274.
  const Start off = start_of(ParameterFile::parse("5210 0\n5211 0.5\n", "o.var"), program);
  EXPECT_EQ(off.g92.offset.x, 0.0);
  EXPECT_EQ(off.g5x.index, 1);
  EXPECT_NEAR(off.machine_mm.x, 1.0, 1e-12);
}

}  // namespace
}  // namespace truecut::interp
