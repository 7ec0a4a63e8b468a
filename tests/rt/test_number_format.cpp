#include "truecut/rt/number_format.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

namespace truecut::rt {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(NumberFormat, ShortestRoundTrips) {
  EXPECT_EQ("0.1", format_shortest(0.1));
  EXPECT_EQ("1", format_shortest(1.0));
  EXPECT_EQ("-2.5", format_shortest(-2.5));
  EXPECT_EQ("0.30000000000000004", format_shortest(0.1 + 0.2));
  EXPECT_EQ("1e+300", format_shortest(1e300));
  EXPECT_EQ("-0", format_shortest(-0.0));  // kept: it reads back as -0
  for (const double v : {1.0 / 3, 2.0 / 3 * 1e-7, 123456.789, -9.87654321e12}) {
    EXPECT_EQ(v, std::stod(format_shortest(v))) << format_shortest(v);
  }
}

TEST(NumberFormat, ShortestPrintsNonFiniteValues) {
  EXPECT_EQ("nan", format_shortest(kNaN));
  EXPECT_EQ("inf", format_shortest(kInf));
  EXPECT_EQ("-inf", format_shortest(-kInf));
}

TEST(NumberFormat, FixedRoundsAndDropsTheSignOfZero) {
  EXPECT_EQ("1.2346", format_fixed(1.23456, 4));
  EXPECT_EQ("-1.2346", format_fixed(-1.23456, 4));
  EXPECT_EQ("2.50", format_fixed(2.5, 2));
  EXPECT_EQ("3", format_fixed(2.5000001, 0));
  EXPECT_EQ("0.000", format_fixed(-0.0, 3));
  EXPECT_EQ("0.000", format_fixed(-0.0004, 3));  // rounds to zero: no "-0.000"
  EXPECT_EQ("-0.001", format_fixed(-0.0005001, 3));
  EXPECT_EQ("0", format_fixed(-0.4, 0));
  EXPECT_EQ("-1", format_fixed(-0.6, 0));
  EXPECT_EQ("1000000.0000", format_fixed(1e6, 4));
}

TEST(NumberFormat, FixedPrintsNonFiniteValuesAsPrintfDoes) {
  EXPECT_EQ("nan", format_fixed(kNaN, 3));
  EXPECT_EQ("inf", format_fixed(kInf, 3));
  EXPECT_EQ("-inf", format_fixed(-kInf, 3));
}

TEST(NumberFormat, PrintfIsNeverTruncated) {
  EXPECT_EQ("1.5e-05", format_printf("%.4g", 1.5e-5));
  EXPECT_EQ("t 1.000–2.500 s", format_printf("t %.3f–%.3f s", 1.0, 2.5));
  EXPECT_EQ("3 of 4", format_printf("%d of %zu", 3, std::size_t(4)));
  EXPECT_EQ(311u, format_printf("%.1f", 1e308).size());  // 309 digits, point, one decimal
  EXPECT_EQ("", format_printf("%s", ""));
  EXPECT_EQ("-0", format_printf("%g", -0.0));  // printf's own: no sign clean-up
}

TEST(NumberFormat, Hex64IsSixteenDigits) {
  EXPECT_EQ("0000000000000000", format_hex64(0));
  EXPECT_EQ("00000000000000ff", format_hex64(255));
  EXPECT_EQ("ffffffffffffffff", format_hex64(~std::uint64_t{0}));
  EXPECT_EQ("0123456789abcdef", format_hex64(0x0123456789abcdefULL));
}

TEST(UtcTimestamp, Iso8601ToTheSecond) {
  EXPECT_EQ("1970-01-01T00:00:00Z", utc_timestamp(0));
  EXPECT_EQ("2023-11-14T22:13:20Z", utc_timestamp(1700000000));
  EXPECT_EQ("2000-02-29T23:59:59Z", utc_timestamp(951868799));
  const std::string now = utc_timestamp_now();
  ASSERT_EQ(20u, now.size()) << now;
  EXPECT_EQ('T', now[10]);
  EXPECT_EQ('Z', now[19]);
}

}  // namespace
}  // namespace truecut::rt
