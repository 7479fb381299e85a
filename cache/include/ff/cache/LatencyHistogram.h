#pragma once

#include <array>
#include <cstdint>

namespace ff::cache {

/**
 * Durations counted in log-spaced buckets, eight to a doubling from 1 µs to 2^24 µs (~17 s;
 * longer ones share the last bucket): memory that does not grow with a run, and quantiles
 * within 9 % (one bucket) of the true value. The page cache counts its fetch-to-resident times
 * here, from the request that queued a read to the install that made the page resident.
 */
class LatencyHistogram {
public:
    /** Counts one duration; negative or NaN counts as 0. */
    void add(double seconds) noexcept;
    std::uint64_t count() const noexcept { return mCount; }
    /** The upper edge, in seconds, of the bucket holding the q-quantile (q in [0, 1]) of what was
     *  counted: never below the true quantile, at most 9 % above it (for durations under
     *  ~17 s and over 1 µs); 0 when nothing was counted. */
    double quantile(double q) const noexcept;

private:
    static constexpr int kPerDoubling = 8;
    static constexpr int kDoublings = 24;
    static constexpr int kBuckets = kPerDoubling * kDoublings + 1;
    std::array<std::uint64_t, kBuckets> mCounts{};
    std::uint64_t mCount = 0;
};

} // namespace ff::cache
