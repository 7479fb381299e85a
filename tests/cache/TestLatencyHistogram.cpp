// LatencyHistogram: quantiles of counted durations, never below the true value and within one
// bucket (9 %) above it, whatever their spread.

#include <ff/cache/LatencyHistogram.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace ff::cache {
namespace {

TEST(LatencyHistogramTest, EmptyHasNoQuantile) {
    const LatencyHistogram h;
    EXPECT_EQ(h.count(), 0u);
    EXPECT_EQ(h.quantile(0.95), 0.0);
}

TEST(LatencyHistogramTest, QuantilesAreWithinABucketAboveTheTrueOnes) {
    // Log-uniform from 10 µs to 10 s: every bucket in between is used.
    std::mt19937 random(7);
    std::uniform_real_distribution<double> exponent(-5.0, 1.0);
    std::vector<double> seconds(20000);
    LatencyHistogram h;
    for (double& s : seconds) {
        s = std::pow(10.0, exponent(random));
        h.add(s);
    }
    std::sort(seconds.begin(), seconds.end());
    EXPECT_EQ(h.count(), seconds.size());
    for (const double q : {0.0, 0.01, 0.5, 0.9, 0.95, 0.99, 1.0}) {
        const auto rank = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(q * static_cast<double>(seconds.size()))));
        const double truth = seconds[rank - 1];
        EXPECT_GE(h.quantile(q), truth) << "q " << q;
        EXPECT_LE(h.quantile(q), truth * std::exp2(1.0 / 8.0)) << "q " << q;
    }
}

TEST(LatencyHistogramTest, OneSlowOutlierMovesOnlyTheTop) {
    LatencyHistogram h;
    for (int i = 0; i < 99; ++i)
        h.add(0.002);
    h.add(3.0);
    EXPECT_LT(h.quantile(0.95), 0.0025);
    EXPECT_GE(h.quantile(1.0), 3.0);
}

TEST(LatencyHistogramTest, NegativeAndNaNCountAsZero) {
    LatencyHistogram h;
    h.add(-1.0);
    h.add(std::numeric_limits<double>::quiet_NaN());
    EXPECT_EQ(h.count(), 2u);
    EXPECT_LE(h.quantile(1.0), 1e-6);
}

} // namespace
} // namespace ff::cache
