// LinuxCNC tool tables.
#include <gtest/gtest.h>

#include <fstream>

#include "test_paths.hpp"
#include "truecut/interp/error.hpp"
#include "truecut/interp/tool_table.hpp"

namespace truecut::interp {
namespace {

TEST(ToolTable, ParsesLinuxCncFormat) {
  auto t = ToolTable::parse(
      "T1 P1 D6.0 Z+10.5 ;6 mm end mill\n"
      "\n"
      "; a comment line\n"
      "t99999 p123 x1 y-2 z0.1 a3 c4 u0 v0 w0 d0 i0 j0 q1\n",
      "tool.tbl");
  ASSERT_EQ(t.entries().size(), 2u);
  const ToolEntry* one = t.find(1);
  ASSERT_TRUE(one);
  EXPECT_EQ(one->pocket, 1);
  EXPECT_DOUBLE_EQ(one->offset_mm.z, 10.5);
  EXPECT_DOUBLE_EQ(one->diameter_mm, 6.0);
  EXPECT_EQ(one->comment, "6 mm end mill");
  const ToolEntry* big = t.find(99999);
  ASSERT_TRUE(big);
  EXPECT_DOUBLE_EQ(big->offset_mm.x, 1);
  EXPECT_DOUBLE_EQ(big->offset_mm.y, -2);
  EXPECT_DOUBLE_EQ(big->offset_mm.c, 4);
  EXPECT_EQ(t.slot_of(99999), 2);
  EXPECT_EQ(t.find(5), nullptr);
}

TEST(ToolTable, ErrorsAreLocated) {
  try {
    ToolTable::parse("T1 P1 Z1\nT2 P2 Zabc\n", "bad.tbl");
    FAIL();
  } catch (const GcodeError& e) {
    EXPECT_EQ(std::string(e.what()), "bad.tbl:2:7: bad number after 'Z' in tool table");
  }
  EXPECT_THROW(ToolTable::parse("P1 Z1\n", "x.tbl"), GcodeError);
  EXPECT_THROW(ToolTable::parse("T1 K4\n", "x.tbl"), GcodeError);
  EXPECT_THROW(ToolTable::load(truecut::test::scratch_dir() / "missing.tbl"), GcodeError);
}

// Entries no tool can have (issue 23: read silently before, NaN tool-centre
// points or a 1e30 tool number cast to int): refused at their line and
// column, with the value and the range.
TEST(ToolTable, ImplausibleEntriesAreRefusedAtTheirColumn) {
  const struct {
    const char* line;
    const char* message;
  } cases[] = {
      {"T1 P1 D-6 Z50", "x.tbl:1:7: diameter D -6 in tool table is outside 0 to 1000"},
      {"T1 P1 D1e9 Z50", "x.tbl:1:7: diameter D 1e+09 in tool table is outside 0 to 1000"},
      {"T1 P1 D6 Z-1e12", "x.tbl:1:10: offset Z (length) -1e+12 in tool table is outside"},
      {"T1 P1 D6 Znan", "x.tbl:1:10: 'Znan' in tool table: not a finite number"},
      {"T1 P1 Dinf", "x.tbl:1:7: 'Dinf' in tool table: not a finite number"},
      {"T1e30 P1 D6", "x.tbl:1:1: tool number T 1e+30 in tool table is outside 0 to 99999"},
      {"T1.5 P1 D6", "x.tbl:1:1: tool number T 1.5 in tool table is not a whole number"},
      {"T-2 P1 D6", "x.tbl:1:1: tool number T -2 in tool table is outside"},
      {"T2 P1e12 D6", "x.tbl:1:4: pocket P 1e+12 in tool table is outside"},
      {"T2 P1 D6 C1e9", "x.tbl:1:10: angular offset 1e+09 in tool table is outside"},
  };
  for (const auto& c : cases) {
    try {
      ToolTable::parse(std::string("T9 P9 D1\n") + c.line + "\n", "x.tbl");
      ADD_FAILURE() << c.line;
    } catch (const GcodeError& e) {
      std::string expected = c.message;
      expected.replace(expected.find(":1:"), 3, ":2:");
      EXPECT_EQ(std::string(e.what()).rfind(expected, 0), 0u) << e.what();
    }
  }
  // The largest plausible values pass.
  const ToolTable t = ToolTable::parse("T99999 P99999 D1000 Z-10000 X10000 C-3600\n", "x.tbl");
  ASSERT_NE(t.find(99999), nullptr);
  EXPECT_EQ(t.find(99999)->diameter_mm, 1000.0);
}

// A tool given twice, or a field given twice on a line, was taken silently
// (the last entry, the last value): refused at the line and column.
TEST(ToolTable, AToolOrAFieldGivenTwiceIsRefused) {
  try {
    ToolTable::parse("T1 P1 D2 Z35\nT2 P2 D6\nT1 P3 D4\n", "x.tbl");
    ADD_FAILURE();
  } catch (const GcodeError& e) {
    EXPECT_EQ(std::string(e.what()),
              "x.tbl:3:1: tool T1 is already in the table at line 1: two entries for one tool "
              "(LinuxCNC keeps the last); remove one");
  }
  try {
    ToolTable::parse("T1 P1 D2.000 Z35 D3\n", "x.tbl");
    ADD_FAILURE();
  } catch (const GcodeError& e) {
    EXPECT_EQ(std::string(e.what()),
              "x.tbl:1:18: field 'D' is given twice on this line (also at column 7): which one "
              "is meant? (LinuxCNC takes the last)");
  }
  EXPECT_NO_THROW(ToolTable::parse("T1 P1 D2\nT2 P1 D2 ; the same pocket is allowed\n", "x.tbl"));
}

// A table in inches (an inch machine's, or rs274's without an INI) is
// stored in mm; its limits are checked in its own units. It was read as mm.
TEST(ToolTable, InchTableIsReadInInchesAndStoredInMm) {
  const ToolTable t =
      ToolTable::parse("T1 P1 X0.05 Z1.5 D0.25 A10\n", "inch.tbl", LengthUnits::kInch);
  const ToolEntry* e = t.find(1);
  ASSERT_NE(nullptr, e);
  EXPECT_DOUBLE_EQ(0.05 * 25.4, e->offset_mm.x);
  EXPECT_DOUBLE_EQ(1.5 * 25.4, e->offset_mm.z);
  EXPECT_DOUBLE_EQ(0.25 * 25.4, e->diameter_mm);
  EXPECT_DOUBLE_EQ(10.0, e->offset_mm.a) << "angles are not lengths";
  try {
    ToolTable::parse("T1 P1 Z500\n", "inch.tbl", LengthUnits::kInch);  // 12.7 m
    FAIL() << "a 500 inch tool";
  } catch (const GcodeError& err) {
    EXPECT_EQ(1, err.where().line);
    EXPECT_NE(std::string::npos, std::string(err.what()).find("500 in tool table is outside"))
        << err.what();
  }
  EXPECT_NO_THROW(ToolTable::parse("T1 P1 Z500\n", "mm.tbl")) << "500 mm is a tool";
}

TEST(ToolTable, LoadsFromFile) {
  const auto file = truecut::test::scratch_dir() / "tool.tbl";
  std::ofstream(file) << "T3 P3 Z7 D2\n";
  EXPECT_DOUBLE_EQ(ToolTable::load(file).find(3)->offset_mm.z, 7);
}

}  // namespace
}  // namespace truecut::interp
