#include <ff/cache/LatencyHistogram.h>

#include <algorithm>
#include <cmath>

namespace ff::cache {

void LatencyHistogram::add(double seconds) noexcept {
    const double micros = seconds * 1e6;
    // Bucket b holds (2^((b-1)/8), 2^(b/8)] µs; bucket 0 everything up to 1 µs.
    int bucket = 0;
    if (micros > 1.0) // also false for NaN
        bucket = std::min(kBuckets - 1, static_cast<int>(std::ceil(std::log2(micros) * kPerDoubling)));
    ++mCounts[static_cast<std::size_t>(bucket)];
    ++mCount;
}

double LatencyHistogram::quantile(double q) const noexcept {
    if (mCount == 0)
        return 0.0;
    // The smallest bucket whose running count reaches ceil(q x count) (at least the first).
    const double wanted = std::clamp(q, 0.0, 1.0) * static_cast<double>(mCount);
    const auto rank = std::max<std::uint64_t>(1, static_cast<std::uint64_t>(std::ceil(wanted)));
    std::uint64_t seen = 0;
    int bucket = 0;
    for (; bucket < kBuckets - 1; ++bucket) {
        seen += mCounts[static_cast<std::size_t>(bucket)];
        if (seen >= rank)
            break;
    }
    return std::exp2(static_cast<double>(bucket) / kPerDoubling) * 1e-6;
}

} // namespace ff::cache
