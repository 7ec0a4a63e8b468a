#include <gtest/gtest.h>

#include "truecut/rt/duration_histogram.hpp"

using truecut::rt::DurationHistogram;

TEST(DurationHistogram, PercentilesOfKnownSamples) {
  DurationHistogram h;
  for (int i = 1; i <= 1000; ++i)
    h.add(i);  // 1..1000 ns, 1 ns bins
  EXPECT_EQ(1000u, h.count());
  EXPECT_EQ(500, h.percentile_ns(0.5));
  EXPECT_EQ(990, h.percentile_ns(0.99));
  EXPECT_EQ(1000, h.percentile_ns(1.0));
  EXPECT_EQ(1, h.min_ns());
  EXPECT_DOUBLE_EQ(500.5, h.mean_ns());
}

TEST(DurationHistogram, CoarseBinsAreBoundedByTheMaximum) {
  DurationHistogram h;
  h.add(20'003);       // 10 ns bin [20000, 20009]
  h.add(2'000'500);    // 1 us bin
  h.add(500'000'000);  // overflow
  EXPECT_EQ(20'009, h.percentile_ns(0.3));
  EXPECT_EQ(2'000'999, h.percentile_ns(0.6));
  EXPECT_EQ(500'000'000, h.percentile_ns(1.0));
  EXPECT_EQ(500'000'000, h.max_ns());
  h.clear();
  EXPECT_EQ(0u, h.count());
  EXPECT_EQ(0, h.percentile_ns(0.5));
}
