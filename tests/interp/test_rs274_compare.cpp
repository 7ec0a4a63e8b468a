// The listing comparison used by the oracle test must see real differences.
#include <gtest/gtest.h>

#include "rs274_compare.hpp"

namespace truecut::interp::testing {
namespace {

const char* kRs274 =
    "executing\n"
    "    1 N..... STRAIGHT_FEED(1.0000, 2.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n"
    " x\n"
    "    2 N0010  ARC_FEED(10.0000, 0.0000, 5.0000, -0.0000, -1, 0.0000, 0.0000, 0.0000, 0.0000)\n"
    "    3 N..... SELECT_PLANE(CANON_PLANE_XY)\n"
    "    4 N..... COMMENT(\"hello\")\n";

TEST(Rs274Compare, ParsesCallsAndIgnoresOtherLines) {
  auto calls = parse_listing(kRs274);
  ASSERT_EQ(calls.size(), 4u);
  EXPECT_EQ(calls[1].name, "ARC_FEED");
  EXPECT_EQ(calls[1].block, "0010");
  EXPECT_EQ(calls[0].block, ".....");
  EXPECT_EQ(calls[3].args, "\"hello\"");
}

TEST(Rs274Compare, AcceptsRoundingOfThePrintedDigits) {
  auto truecut = parse_listing(
      "1 N..... STRAIGHT_FEED(1.00004999, 1.99995001, 0.00000000, 0, 0, 0)\n"
      "2 N0010  ARC_FEED(10.0, 0.0, 5.0, 0.0, -1, 0.0, 0.0, 0.0, 0.0)\n"
      "3 N..... SELECT_PLANE(CANON_PLANE_XY)\n4 N..... COMMENT(\"hello\")\n");
  EXPECT_EQ(compare_listings(parse_listing(kRs274), truecut), std::nullopt);
}

TEST(Rs274Compare, FindsEachKindOfDifference) {
  const auto ref = parse_listing(kRs274);
  auto with = [&](const std::string& first) {
    return parse_listing(first + "\n" +
                         "2 N0010  ARC_FEED(10.0, 0.0, 5.0, 0.0, -1, 0.0, 0.0, 0.0, 0.0)\n"
                         "3 N..... SELECT_PLANE(CANON_PLANE_XY)\n4 N..... COMMENT(\"hello\")\n");
  };
  EXPECT_NE(compare_listings(ref, with("1 N..... STRAIGHT_FEED(1.00006, 2, 0, 0, 0, 0)")),
            std::nullopt);
  EXPECT_NE(compare_listings(ref, with("1 N..... STRAIGHT_TRAVERSE(1, 2, 0, 0, 0, 0)")),
            std::nullopt);
  EXPECT_NE(compare_listings(ref, with("1 N..... STRAIGHT_FEED(1, 2, 0, 0, 0)")), std::nullopt);
  auto plane = parse_listing(
      "1 N..... STRAIGHT_FEED(1, 2, 0, 0, 0, 0)\n"
      "2 N0010  ARC_FEED(10.0, 0.0, 5.0, 0.0, 1, 0.0, 0.0, 0.0, 0.0)\n");
  EXPECT_NE(compare_listings(ref, plane), std::nullopt);  // rotation and length differ
  auto text = parse_listing(
      "1 N..... STRAIGHT_FEED(1, 2, 0, 0, 0, 0)\n"
      "2 N0010  ARC_FEED(10.0, 0.0, 5.0, 0.0, -1, 0.0, 0.0, 0.0, 0.0)\n"
      "3 N..... SELECT_PLANE(CANON_PLANE_XZ)\n4 N..... COMMENT(\"hello\")\n");
  EXPECT_NE(compare_listings(ref, text), std::nullopt);
  auto block = parse_listing(
      "1 N..... STRAIGHT_FEED(1, 2, 0, 0, 0, 0)\n"
      "2 N10    ARC_FEED(10.0, 0.0, 5.0, 0.0, -1, 0.0, 0.0, 0.0, 0.0)\n"
      "3 N..... SELECT_PLANE(CANON_PLANE_XY)\n4 N..... COMMENT(\"hello\")\n");
  EXPECT_NE(compare_listings(ref, block), std::nullopt) << "N0010 is printed as written";
  const auto long_number = parse_listing("    7 N123456STRAIGHT_TRAVERSE(1.0000, 0.0000)\n");
  ASSERT_EQ(long_number.size(), 1u);
  EXPECT_EQ(long_number[0].block, "123456");
  EXPECT_EQ(long_number[0].name, "STRAIGHT_TRAVERSE");
}

}  // namespace
}  // namespace truecut::interp::testing
