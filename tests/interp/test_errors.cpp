// Bad input: every error names file:line:column and stops the program.
#include <gtest/gtest.h>

#include <fstream>

#include "interp_test_util.hpp"
#include "test_names.hpp"
#include "test_paths.hpp"

namespace truecut::interp::testing {
namespace {

struct Case {
  const char* text;
  int line;
  int column;
  const char* message_part;
};

class BadInput : public ::testing::TestWithParam<Case> {};

// The expected message and the case's index (messages repeat), e.g. "unknown_word_W_0".
std::string case_name(const ::testing::TestParamInfo<Case>& info) {
  return truecut::test::test_name(info.param.message_part) + "_" + std::to_string(info.index);
}

TEST_P(BadInput, IsLocated) {
  const Case& c = GetParam();
  GcodeError e = error_of(c.text);
  EXPECT_EQ(e.where().file, "test.ngc");
  EXPECT_EQ(e.where().line, c.line) << e.what();
  EXPECT_EQ(e.where().column, c.column) << e.what();
  EXPECT_NE(e.message().find(c.message_part), std::string::npos) << e.what();
  const std::string prefix =
      "test.ngc:" + std::to_string(c.line) + ":" + std::to_string(c.column) + ": ";
  EXPECT_EQ(std::string(e.what()).rfind(prefix, 0), 0u) << e.what();
}

INSTANTIATE_TEST_SUITE_P(Words, BadInput,
                         ::testing::Values(Case{"G0 X1\nG0 X2 W3\nM2\n", 2, 7, "unknown word W"},
                                           Case{"G0 X1 $\nM2\n", 1, 7, "unknown character '$'"},
                                           Case{"G12.5 X1\nM2\n", 1, 1, "unknown G code G12.5"},
                                           Case{"M123\nM2\n", 1, 1, "M123 is not supported"},
                                           Case{"G0 X1 X2\nM2\n", 1, 7, "two X words"},
                                           Case{"G19\nG41 G0 X1\nM2\n", 2, 1,
                                                "only in the XY (G17) and XZ (G18) planes"},
                                           Case{"G0 X1 D3\nM2\n", 1, 7, "D word with no G41"},
                                           Case{"G1.3 X1\nM2\n", 1, 1, "unknown G code"},
                                           Case{"G0 X\nM2\n", 1, 4, "has no value"},
                                           Case{"X1\nM2\n", 1, 1, "no motion mode"},
                                           Case{"G0 I1 X2\nM2\n", 1, 4, "I word with no G2 or G3"},
                                           Case{"G0 X1 Y2 % \nM2\n", 1, 10, "unknown character"}),
                         case_name);

// LinuxCNC codes truecut refuses by name (docs/gcode.md, the code table):
// lathe modes and cycles, the UVW planes, reloading the tool table, the
// pallet change and user M codes.
INSTANTIATE_TEST_SUITE_P(
    RefusedByName, BadInput,
    ::testing::Values(Case{"G7\nM2\n", 1, 1, "lathe diameter mode (G7) is not supported"},
                      Case{"G8\nM2\n", 1, 1, "lathe radius mode (G8) is not supported"},
                      Case{"G10 L0\nM2\n", 1, 5, "G10 L0 (reload the tool table)"},
                      Case{"G17.1\nM2\n", 1, 1, "UV plane (G17.1) is not supported"},
                      Case{"G18.1\nM2\n", 1, 1, "WU plane (G18.1) is not supported"},
                      Case{"G19.1\nM2\n", 1, 1, "VW plane (G19.1) is not supported"},
                      Case{"G70 Q1\nM2\n", 1, 1, "lathe finishing cycle (G70) is not supported"},
                      Case{"G71 Q1\nM2\n", 1, 1, "lathe roughing cycle (G71) is not supported"},
                      Case{"G71.1 Q1\nM2\n", 1, 1, "lathe roughing cycle (G71.1)"},
                      Case{"G71.2 Q1\nM2\n", 1, 1, "lathe roughing cycle (G71.2)"},
                      Case{"G72 Q1\nM2\n", 1, 1, "lathe facing cycle (G72) is not supported"},
                      Case{"G72.1 Q1\nM2\n", 1, 1, "lathe facing cycle (G72.1)"},
                      Case{"G72.2 Q1\nM2\n", 1, 1, "lathe facing cycle (G72.2)"},
                      Case{"G76 P1 Z-1 I-0.1 J0.1 K0.2\nM2\n", 1, 1,
                           "threading cycle (G76) is not supported"},
                      Case{"M60\nM2\n", 1, 1, "pallet change pause (M60) is not supported"},
                      Case{"M100\nM2\n", 1, 1, "user M code M100 is not supported"},
                      Case{"M199 P1\nM2\n", 1, 1, "user M code M199 is not supported"},
                      Case{"M428\nM2\n", 1, 1, "unknown M code M428"},
                      Case{"G1 U1 F100\nM2\n", 1, 4, "unknown word U"},
                      Case{"G1 B1 F100\nM2\n", 1, 4, "B is rejected"}),
    case_name);

// Computed O-word labels (o[expr], o#n) are read as rs274 reads them: a
// whole number, evaluated when the line is met or sought.
INSTANTIATE_TEST_SUITE_P(
    ComputedLabels, BadInput,
    ::testing::Values(Case{"#1 = 100.5\no[#1] call\nM2\no100 sub\no100 endsub\n", 2, 2,
                           "computed O-word label 100.5 is not a whole number"},
                      Case{"#1 = 7\no[#1] if [1]\no7 endif\no[#1/0] call\nM2\n", 4, 5,
                           "division by zero"},
                      Case{"#1 = 7\no[#1] if [0]\n#1 = 8\no8 endif\nM2\n", 2, 1,
                           "no matching o7 elseif or else or endif"},
                      Case{"#<n> = 400\no#<n> call\nM2\no[#<n>] sub\no[#<n>] endsub\n", 2, 1,
                           "unknown subroutine o400"}),
    case_name);

// Found by fuzz_gcode and fuzz_expression (tools/fuzz.sh): values too large
// for an int were converted to one (undefined behaviour).
INSTANTIATE_TEST_SUITE_P(
    FuzzFindings, BadInput,
    ::testing::Values(
        Case{"G21\nG2177777777777777777777 X1\nM2\n", 2, 1,
             "G code 2177777777777777836032 does not exist"},
        Case{"M99999999999999999999\nM2\n", 1, 1, "does not exist"},
        Case{"G0 Y[-#99999999999999999999999999999]\nM2\n", 1, 8, "value 1e+29 is too large"},
        // Whole-number words beyond int (a float-to-int
        // conversion UBSan caught in fuzz_expression).
        Case{"T[2222222222222222222222222222222]\nM2\n", 1, 1,
             "tool T2.222222222222222e+30 is not in the tool "
             "table"},
        Case{"M61 Q3000000000\nM2\n", 1, 5, "tool 3e+09 is not in the tool table"},
        Case{"G43 H3000000000\nM2\n", 1, 5, "H3e+09: no such tool"},
        Case{"G17 G41 D3000000000\nM2\n", 1, 9, "D3e+09: no such tool"},
        Case{"F100\nG2 X10 I5 P3000000000\nM2\n", 2, 11, "arc turns P 3e+09 is too large"}),
    case_name);

INSTANTIATE_TEST_SUITE_P(
    ModalConflicts, BadInput,
    ::testing::Values(Case{"G0 G1 X1 F100\nM2\n", 1, 4, "same modal group on one line: G0 and G1"},
                      Case{"G17 G18\nM2\n", 1, 5, "same modal group"},
                      Case{"G20 G21\nM2\n", 1, 5, "same modal group"},
                      Case{"G90 G91\nM2\n", 1, 5, "same modal group"},
                      Case{"M3 M5\nM2\n", 1, 4, "same modal group on one line: M3 and M5"},
                      Case{"G4 P1 G92 X0\nM2\n", 1, 7, "two non-modal"}),
    case_name);

INSTANTIATE_TEST_SUITE_P(
    Arcs, BadInput,
    ::testing::Values(Case{"F100\nG2 X10 Y0\nM2\n", 2, 1, "missing arc data"},
                      Case{"F100\nG2 X10 Y0 R5 I5\nM2\n", 2, 11, "both R and I/J/K"},
                      Case{"F100\nG2 X10 Y0 I4 J0\nM2\n", 2, 11, "radius mismatch"},
                      Case{"F100\nG2 X30 Y0 R5\nM2\n", 2, 11, "too small"},
                      Case{"F100\nG2 X0 Y0 R5\nM2\n", 2, 10, "cannot end where it starts"},
                      Case{"F100\nG2 X10 I5 K1\nM2\n", 2, 11, "K word given for an arc in the XY"},
                      Case{"F100\nG2 X10 I5 P0\nM2\n", 2, 11, "turns P"}),
    case_name);

INSTANTIATE_TEST_SUITE_P(
    Feed, BadInput,
    ::testing::Values(Case{"G1 X10\nM2\n", 1, 1, "zero feed rate"},
                      Case{"G0 X1\nG3 X0 Y1 I-1\nM2\n", 2, 1, "zero feed rate"},
                      Case{"G93 G1 X1 F10\nG1 X2\nM2\n", 2, 1, "needs an F word"},
                      Case{"G1 X1 F-5\nM2\n", 1, 7, "negative feed"}),
    case_name);

// Canned cycles (docs/gcode.md "Canned cycles"): the errors LinuxCNC's
// rs274 reports for the same programs, located at the word or the cycle.
INSTANTIATE_TEST_SUITE_P(
    CannedCycles, BadInput,
    ::testing::Values(
        Case{"G0 Z10\nG81 X1 Z-1 F100\nM2\n", 2, 1, "G81 needs R (the retract plane)"},
        Case{"G0 Z10\nG81 X1 R2 F100\nM2\n", 2, 1, "G81 needs Z (the hole bottom)"},
        Case{"G0 Z10\nG18 G81 X1 Z1 R2 F100\nM2\n", 2, 5, "G81 needs Y (the hole bottom)"},
        Case{"G0 Z10\nG81 X1 Z3 R2 F100\nM2\n", 2, 11,
             "R (the retract plane, 2) is below the hole bottom Z (3)"},
        Case{"G0 Z10\nG83 X1 Z-3 R2 F100\nM2\n", 2, 1, "G83 needs Q (the peck depth)"},
        Case{"G0 Z10\nG73 X1 Z-3 R2 F100\nM2\n", 2, 1, "G73 needs Q (the peck depth)"},
        Case{"G0 Z10\nG83 X1 Z-3 R2 Q0 F100\nM2\n", 2, 15, "Q (the peck depth) must be greater"},
        Case{"G0 Z10\nG82 X1 Z-3 R2 F100\nM2\n", 2, 1, "G82 needs P (the dwell in seconds)"},
        Case{"G0 Z10\nG81 X1 Z-3 R2 L0 F100\nM2\n", 2, 15, "L (repeats of the canned cycle)"},
        Case{"G0 Z10\nG81 X1 Z-3 R2 L1.5 F100\nM2\n", 2, 15, "must be a whole number >= 1"},
        Case{"G0 Z10\nG91 G81 X1 Z-3 R2 L100000000 F100\nM2\n", 2, 19,
             "L 1e+08: more than 1e+07 repeats of a canned cycle on one line"},
        Case{"G0 Z10\nG83 X1 Z-3 R2 Q0.0000001 F100\nM2\n", 2, 15,
             "moves of canned cycle G83 on one line (the cycle budget)"},
        Case{"G0 Z10\nG91 G73 X1 Z-3 R2 Q0.001 L100000 F100\nM2\n", 2, 19,
             "moves of canned cycle G73 on one line (the cycle budget)"},
        Case{"G0 Z10\nG81 X1 Z-3 R2 A5 F100\nM2\n", 2, 15, "A word in canned cycle G81"},
        Case{"G0 Z10\nG81 X1 Z-3 R2\nM2\n", 2, 1, "G81 with a zero feed rate"},
        Case{"G0 Z10\nG93 G81 X1 Z-3 R2 F10\nM2\n", 2, 5, "inverse-time feed (G93)"},
        Case{"G0 Z10\nG86 X1 Z-3 R2 P1 F100\nM2\n", 2, 1, "G86 needs the spindle turning"},
        Case{"M3 S100\nG0 Z10\nG88 X1 Z-3 R2 P1 F100\nM5\nX2\nM2\n", 5, 1,
             "G88 needs the spindle turning"},
        Case{"G0 Z10\nG81 X1 Z-3 R2 Q1 F100\nM2\n", 2, 15, "Q word with no code that uses it"},
        Case{"G0 Z10\nG81 X1 Z-3 R2 P1 F100\nM2\n", 2, 15, "P word with no code that uses it"},
        Case{"G0 Z10\nG81 X1 Z-3 R2 I1 F100\nM2\n", 2, 15, "I word in a canned cycle"},
        // The sticky R and Z belong to the cycle that set them.
        Case{"G0 Z10\nG81 X1 Z-3 R2 F100\nG82 X2 P1\nM2\n", 3, 1, "G82 needs R"},
        Case{"G0 Z10\nG81 X1 Z-3 R2 F100\nG0 X0\nG81 X2\nM2\n", 4, 1, "G81 needs R"},
        // Tapping and back boring (G74 G84 G87).
        Case{"G0 Z10\nG84 X1 Z-3 R2 F100\nM2\n", 2, 1, "G84 needs the spindle turning (M3)"},
        Case{"M3 S100\nG0 Z10\nG74 X1 Z-3 R2 F100\nM2\n", 3, 1,
             "G74 (left-hand tapping) with the spindle turning clockwise"},
        Case{"M4 S100\nG0 Z10\nG84 X1 Z-3 R2 F100\nM2\n", 3, 1,
             "G84 (right-hand tapping) with the spindle turning counterclockwise"},
        Case{"M3 S100\nG18 G0 Y10\nG84 X1 Z1 Y-3 R2 F100\nM2\n", 3, 1,
             "G84 (tapping) outside the XY plane (G17)"},
        Case{"M4 S100\nG19 G0 X10\nG74 Y1 Z1 X-3 R2 F100\nM2\n", 3, 1,
             "G74 (tapping) outside the XY plane (G17)"},
        Case{"M3 S100\nG0 Z10\nG84 X1 Z-3 R2 P-1 F100\nM2\n", 3, 15,
             "dwell time P must not be negative"},
        Case{"G0 Z10\nG87 X1 Z-3 R2 I1 J0 K1 F100\nM2\n", 2, 1, "G87 needs the spindle turning"},
        Case{"M3 S100\nG0 Z10\nG87 X1 Z-3 R2 I1 K1 F100\nM2\n", 3, 1, "G87 needs J"},
        Case{"M3 S100\nG0 Z10\nG87 X1 Z-3 R2 I1 J1 F100\nM2\n", 3, 1, "G87 needs K"},
        Case{"M3 S100\nG0 Z10\nG81 X1 Z-3 R2 F100\nG87 X2 I1 J1 K1\nM2\n", 4, 1, "G87 needs R"},
        Case{"M3 S100\nG0 Z10\nG84 X1 Z-3 R2 I1 F100\nM2\n", 3, 15, "I word in a canned cycle"},
        // Spindle-synchronised motion and probing: truecut's own refusals.
        Case{"M3 S100\nG33 Z-3 K0\nM2\n", 2, 9, "K (the distance per spindle revolution) must be"},
        Case{"M3 S100\nG33.1 Z-3 K-1\nM2\n", 2, 11, "must be greater than 0"},
        Case{"M3 S100\nG33.1 Z-3 A5 K1\nM2\n", 2, 11, "A word with G33.1"},
        Case{"G0 Z5\nG93 G38.2 Z-3 F1\nM2\n", 2, 5, "G38.2 with inverse-time feed (G93)"},
        // Fanuc-style subprograms: what truecut refuses where rs274 ignores
        // words or reports another line (docs/gcode.md).
        Case{"G0 Z5\nM98 P100 F200\nM2\nO100\nG1 X1 F100\nM99\n", 2, 1,
             "M98 must be alone on its line (with P and L)"},
        Case{"G0 Z5\nM98 P300\nM2\nO100\nG1 X1 F100\nM99\n", 2, 1,
             "M98 P300: no subprogram O300 in the program"},
        Case{"G0 Z5\no100 call\nM2\no100 sub\nM99\no100 endsub\n", 5, 1,
             "M99 in the O-word subroutine o100 (use endsub)"},
        Case{"G0 Z5\nM98 P100\nM2\nO100\no100 endsub\n", 5, 1,
             "endsub in the subprogram O100 (called by M98: use M99)"}),
    case_name);

// Polar coordinates (docs/gcode.md "Polar coordinates"): the programs
// LinuxCNC's rs274 refuses, and the two truecut refuses where rs274 would
// take the last word or mix the polar point with the drilling axis.
INSTANTIATE_TEST_SUITE_P(
    Polar, BadInput,
    ::testing::Values(
        Case{"G18\nG0 ^10\nM2\n", 2, 4, "only in the XY plane: the plane before this line is XZ"},
        Case{"G18\nG17 G0 @1 ^10\nM2\n", 2, 8, "only in the XY plane"},
        Case{"G1 @10 X5 F100\nM2\n", 1, 8, "polar coordinates (@ ^) and the X word"},
        Case{"G1 Y1 ^10 F100\nM2\n", 1, 4, "polar coordinates (@ ^) and the Y word"},
        Case{"G0 @5\nM2\n", 1, 4, "@ without ^ at the origin"},
        Case{"G0 X3 Y4\nG0 @0\nG0 @5\nM2\n", 3, 4, "@ without ^ at the origin"},
        Case{"G91 G0 @1 ^1\nM2\n", 1, 8, "incremental polar coordinates (G91 @ ^) at the origin"},
        Case{"G91 G0 ^90\nM2\n", 1, 8, "incremental polar coordinates"},
        Case{"G92 @1\nM2\n", 1, 5, "for motion only"},
        Case{"G10 L2 P1 ^1\nM2\n", 1, 11, "for motion only"},
        Case{"G28 @1\nM2\n", 1, 5, "for motion only"}, Case{"G53 G0 @1 ^0\nM2\n", 1, 8, "with G53"},
        Case{"@5 ^1\nM2\n", 1, 1, "no motion mode"},
        Case{"G0 @1 @2\nM2\n", 1, 7, "two @ words on one line"},
        Case{"G0 ^1 ^2\nM2\n", 1, 7, "two ^ words on one line"},
        Case{"G0 @\nM2\n", 1, 4, "word @ has no value"},
        Case{"G0 X5 Z5\nG18 G81 @1 ^0 R1 F10\nM2\n", 2, 9,
             "polar coordinates (@ ^) in canned cycle G81 outside the XY plane"},
        Case{"G2 @1 ^1 F10\nM2\n", 1, 1, "missing arc data"},
        Case{"G0 X1\nG91 G0 @[10 ** 308]\n@[10 ** 308]\nM2\n", 3, 1, "the polar point overflows"}),
    case_name);

// M70-M73 (docs/gcode.md "Modal state"): M72 needs a state saved at its
// call level; M70-M73 share the spindle's modal group, as in LinuxCNC.
INSTANTIATE_TEST_SUITE_P(
    ModalState, BadInput,
    ::testing::Values(
        Case{"M72\nM2\n", 1, 1, "M72 with no modal state saved at this call level"},
        Case{"M70\nM71\nM72\nM2\n", 3, 1, "M72 with no modal state saved"},
        Case{"o1 sub\nM72\no1 endsub\nM70\no1 call\nM2\n", 2, 1, "M72 with no modal state saved"},
        Case{"o1 sub\nM70\no1 endsub\no1 call\nM72\nM2\n", 5, 1, "M72 with no modal state saved"},
        Case{"o1 sub\nM70\no1 endsub\no1 call\no2 sub\nM72\no2 endsub\no1 call\no2 call\nM2\n", 6,
             1, "M72 with no modal state saved"},
        Case{"M70 M3\nM2\n", 1, 5, "same modal group on one line: M70 and M3"},
        Case{"M70 M72\nM2\n", 1, 5, "same modal group on one line: M70 and M72"},
        Case{"M70\nM72 G0 X1\nM2\n", 2, 1, "M72 with G codes, axis words"},
        Case{"M70\nM72 M8\nM2\n", 2, 1, "put M72 on a line of its own"},
        Case{"M70\nM72 M2\n", 2, 1, "put M72 on a line of its own"}),
    case_name);

// Cutter radius compensation (docs/gcode.md "Cutter radius compensation");
// Rs274Oracle.CutterCompErrorsAtTheSameLine checks the lines against rs274.
// Tool T1 has D6 (radius 3 mm).
INSTANTIATE_TEST_SUITE_P(
    CutterComp, BadInput,
    ::testing::Values(
        Case{"G0 X0 Y0\nG41 D1 G1 X2 F100\nM2\n", 2, 8,
             "entry move is not longer than the tool radius"},
        Case{"G0 X0 Y0\nG41 D1 G1 X20 F100\nT2 M6\nM2\n", 3, 4,
             "cannot change tools with cutter radius compensation on"},
        Case{"G0 X0 Y0\nG41 D1 G1 X20 F100\nG20\nM2\n", 3, 1,
             "changing units (G20/G21) with cutter radius compensation on is not supported"},
        Case{"G0 X0 Y0\nG41 D1 G1 X20 F100\nG40\nG2 X0 Y0 R20\nM2\n", 4, 1,
             "must be straight, not an arc"},
        Case{"G0 X0 Y0\nG41 D1 G1 X20 F100\nG1 X20 Y1\nG1 X0 Y1\nM2\n", 4, 1,
             "straight feed in a concave corner cannot be reached by the tool without gouging"},
        Case{"G41 D2.5 G1 X20 F100\nM2\n", 1, 5, "G41 needs D to be a whole number"},
        Case{"G41 D5 G1 X20 F100\nM2\n", 1, 5, "tool 5 for G41 is not in the tool table"},
        Case{"G41.1 D2 L3 G1 X20 F100\nM2\n", 1, 10,
             "G41.1 with an L word, but the plane is not G18"},
        Case{"G18 G41.1 D2 L3 G1 X20 F100\nM2\n", 1, 14,
             "L (lathe tool orientation 1-8) is not supported"},
        Case{"G41 D1 G1 X20 F100\nG81 X5 R1 Z-1\nM2\n", 2, 1,
             "cannot use canned cycles with cutter radius compensation on"}),
    case_name);

INSTANTIATE_TEST_SUITE_P(
    Expressions, BadInput,
    ::testing::Values(Case{"G0 X[1 + [2]\nM2\n", 1, 5, "unbalanced brackets"},
                      Case{"G0 X[1 + 2]]\nM2\n", 1, 12, "unbalanced brackets"},
                      Case{"#1 = 0\nG0 X[4 / #1]\nM2\n", 2, 8, "division by zero"},
                      Case{"G0 X[4 MOD 0]\nM2\n", 2 - 1, 8, "division by zero"},
                      Case{"#1 5\nM2\n", 1, 5, "expected '='"},
                      Case{"G0 X1 (unclosed\nM2\n", 1, 7, "unclosed comment"},
                      Case{"G0 X1 (a (b) c)\nM2\n", 1, 10, "nested comment"}),
    case_name);

INSTANTIATE_TEST_SUITE_P(Program, BadInput,
                         ::testing::Values(Case{"G0 X1\nG0 X2\n", 2, 1, "no program end"},
                                           Case{"G0 X1\n%\nM2\n", 2, 1, "'%'"},
                                           Case{"G0 X1\nT9 M6\nM2\n", 2, 1,
                                                "not in the tool table"},
                                           Case{"G43 H8\nM2\n", 1, 5, "not in the tool table"}),
                         case_name);

// A lathe tool (orientation Q1-Q8 in the tool table) for G41/G42: rs274's
// error outside G18; refused by name in G18 (truecut is for mills).
TEST(BadInput, CutterCompWithALatheToolIsRefused) {
  InterpreterOptions o;
  o.tools = ToolTable::parse("T1 P1 D6 Z10\nT4 P4 D0.8 Q3\n", "tools.tbl");
  EXPECT_EQ(o.tools.find(4)->orientation, 3);
  const GcodeError plane = error_of("G0 X0 Y0\nG41 D4 G1 X20 F100\nM2\n", o);
  EXPECT_EQ(plane.where().line, 2);
  EXPECT_NE(plane.message().find("with a lathe tool (orientation Q3 in the tool table), but the "
                                 "plane is not G18"),
            std::string::npos)
      << plane.what();
  const GcodeError lathe = error_of("G18 G0 X0 Z0\nG42 D4 G1 X20 F100\nM2\n", o);
  EXPECT_EQ(lathe.where().line, 2);
  EXPECT_NE(lathe.message().find("is not supported: truecut is for mills"), std::string::npos)
      << lathe.what();
  // Q0 and Q9 are mills: compensation runs.
  o.tools = ToolTable::parse("T1 P1 D6 Z10 Q9\n", "tools.tbl");
  EXPECT_NO_THROW(run("G0 X0 Y0\nG41 D1 G1 X20 F100\nG40 G1 X30\nM2\n", o));
}

TEST(BadInput, NotTextIsRejectedBeforeAnything) {
  const std::string binary("\x89PNG\r\n\x1a\n\0\0\0\rIHDR", 16);
  try {
    run(binary);
    FAIL() << "binary accepted";
  } catch (const GcodeError& e) {
    EXPECT_EQ(e.where().line, 2);
    EXPECT_NE(e.message().find("not a text file"), std::string::npos);
  }
}

// M62-M68, M19, M50-M53: words rs274 takes (it rounds a fraction, passes a
// negative output number on, reads a missing Q as -1, any P but 0 as on)
// and truecut refuses at their column (docs/gcode.md).
TEST(BadInput, IoWordsRs274PassesOnAreRefused) {
  const Case cases[] = {
      {"M62 P1.5\nM2\n", 1, 5, "M62 P (the output number) must be a whole number"},
      {"M64 P-1\nM2\n", 1, 5, "M64 P (the output number) must be a whole number"},
      {"M67 E0\nM2\n", 1, 1, "M67 needs Q"},
      {"M68 E1.5 Q1\nM2\n", 1, 5, "M68 E (the output number)"},
      {"M50 P2\nM2\n", 1, 5, "M50 P (0 off, 1 on)"},
      {"M66 P0 L5 Q1\nM2\n", 1, 8, "M66 L (the wait mode) must be a whole number from 0 to 4"},
      {"M19 R10 P3\nM2\n", 1, 9, "M19 P (the direction)"},
      {"M19 R10 Q-1\nM2\n", 1, 9, "M19 Q (the timeout) must not be negative"},
      {"G0 X1 E2\nM2\n", 1, 7, "E word with no M66, M67 or M68"},
      {"M19 L2\nM2\n", 1, 5, "L word with no G10"},
  };
  for (const Case& c : cases) {
    GcodeError e = error_of(c.text);
    EXPECT_EQ(e.where().line, c.line) << c.text << e.what();
    EXPECT_EQ(e.where().column, c.column) << c.text << e.what();
    EXPECT_NE(e.message().find(c.message_part), std::string::npos) << e.what();
  }
}

TEST(BadInput, NoPartialResult) {
  // The API returns nothing for a program with an error: run_text throws.
  EXPECT_THROW(run("G0 X1\nG0 X2\nG2 X1\nM2\n"), GcodeError);
}

}  // namespace
}  // namespace truecut::interp::testing

// A subroutine file loaded by a call used to move the files read before it
// in memory: an error on a later line of the main program then named its
// file through a dangling pointer (garbage, or std::bad_alloc).
TEST(BadInput, ErrorAfterASubroutineFileWasLoadedNamesTheMainProgram) {
  const auto dir = truecut::test::scratch_dir();
  std::ofstream(dir / "side.ngc") << "o<side> sub\n  G1 X1 F500\no<side> endsub\nM2\n";
  std::ofstream(dir / "main.ngc") << "G0 X0 Y0\no<side> call\nG2 X0 Y5 I1 J0\nM2\n";
  try {
    truecut::interp::Interpreter().run_file(dir / "main.ngc");
    FAIL() << "the arc's radii differ";
  } catch (const truecut::interp::GcodeError& e) {
    EXPECT_EQ((dir / "main.ngc").string(), e.where().file);
    EXPECT_EQ(3, e.where().line);
  }
}
