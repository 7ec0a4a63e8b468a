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

TEST(ToolTable, LoadsFromFile) {
  const auto file = truecut::test::scratch_dir() / "tool.tbl";
  std::ofstream(file) << "T3 P3 Z7 D2\n";
  EXPECT_DOUBLE_EQ(ToolTable::load(file).find(3)->offset_mm.z, 7);
}

}  // namespace
}  // namespace truecut::interp
