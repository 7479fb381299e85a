// The one percentile behind every p50/p95/p99 (replay, benchmarks): nearest rank. The copy in
// replay once read p = 0 as the maximum (an index of -1 wrapped around).

#include <ff/runtime/Percentile.h>

#include <gtest/gtest.h>

namespace ff::runtime {
namespace {

TEST(PercentileTest, IsTheNearestRankFromTheMinimumToTheMaximum) {
    const std::vector<double> values = {5, 1, 4, 2, 3}; // sorted: 1 2 3 4 5
    EXPECT_EQ(percentile(values, 0.0), 1.0);
    EXPECT_EQ(percentile(values, 0.2), 1.0); // rank ceil(1.0) = 1
    EXPECT_EQ(percentile(values, 0.21), 2.0);
    EXPECT_EQ(percentile(values, 0.5), 3.0);
    EXPECT_EQ(percentile(values, 0.95), 5.0);
    EXPECT_EQ(percentile(values, 1.0), 5.0);
    EXPECT_EQ(percentile({}, 0.5), 0.0);
    EXPECT_EQ(percentile({7.0}, 0.0), 7.0);
}

} // namespace
} // namespace ff::runtime
