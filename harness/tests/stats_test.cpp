// Summary statistics and the order-statistics interval for the median.
#include <gtest/gtest.h>

#include <cmath>

#include "util/stats.h"

namespace accelbench {
namespace {

TEST(StatsTest, MedianMeanStddev) {
    const Summary s = summarize({3, 1, 2, 10});
    EXPECT_EQ(s.n, 4u);
    EXPECT_DOUBLE_EQ(s.median, 2.5);
    EXPECT_DOUBLE_EQ(s.mean, 4.0);
    EXPECT_NEAR(*s.stddev, std::sqrt((1 + 9 + 4 + 36) / 3.0), 1e-12);
    EXPECT_DOUBLE_EQ(summarize({5, 1, 3}).median, 3);
}

TEST(StatsTest, OneSampleHasNoSpreadOrInterval) {
    const Summary s = summarize({0.25});
    EXPECT_EQ(s.median, 0.25);
    EXPECT_FALSE(s.stddev);
    EXPECT_FALSE(s.ci_lo);
    EXPECT_FALSE(s.coverage);
    EXPECT_THROW(summarize({}), std::invalid_argument);
}

TEST(StatsTest, CoverageIsTheBinomialSum) {
    EXPECT_DOUBLE_EQ(median_interval_coverage(3, 1), 0.75);  // 6/8
    EXPECT_DOUBLE_EQ(median_interval_coverage(5, 1), 30.0 / 32);
    EXPECT_NEAR(median_interval_coverage(10, 2), (1024.0 - 2 * (1 + 10)) / 1024, 1e-12);
    EXPECT_NEAR(median_interval_coverage(10, 3), (1024.0 - 2 * (1 + 10 + 45)) / 1024, 1e-12);
    EXPECT_EQ(median_interval_coverage(4, 3), 0.0);
}

TEST(StatsTest, IntervalIsTheNarrowestReaching95Percent) {
    // n = 3 and 5 cannot reach 95%: [min, max] with its true coverage.
    Summary s = summarize({2, 1, 3});
    EXPECT_EQ(*s.ci_lo, 1);
    EXPECT_EQ(*s.ci_hi, 3);
    EXPECT_DOUBLE_EQ(*s.coverage, 0.75);
    s = summarize({1, 2, 3, 4, 5, 6});
    EXPECT_EQ(*s.ci_lo, 1);
    EXPECT_EQ(*s.ci_hi, 6);
    EXPECT_GE(*s.coverage, 0.95);
    // n = 10: k = 2 covers 97.9%, k = 3 only 89%: [x(2), x(9)].
    s = summarize({10, 9, 8, 7, 6, 5, 4, 3, 2, 1});
    EXPECT_EQ(*s.ci_lo, 2);
    EXPECT_EQ(*s.ci_hi, 9);
    EXPECT_NEAR(*s.coverage, 1002.0 / 1024, 1e-12);
    // Large n stays finite and near the normal approximation's width.
    std::vector<double> many;
    for (int i = 0; i < 2000; ++i) many.push_back(i);
    s = summarize(many);
    EXPECT_GE(*s.coverage, 0.95);
    EXPECT_NEAR(*s.ci_lo, 1000 - 1.96 * std::sqrt(2000.0) / 2, 3);
}

}  // namespace
}  // namespace accelbench
