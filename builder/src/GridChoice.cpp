#include <ff/builder/GridChoice.h>
#include <ff/storage/Assert.h>

#include <algorithm>
#include <cmath>

namespace ff::builder {

void EdgeSampler::add(std::span<const storage::PackedTriangle> triangles) {
    for (const storage::PackedTriangle& t : triangles) {
        for (std::size_t e = 0; e < 3; ++e) {
            const auto& a = t.vertices[e].position;
            const auto& b = t.vertices[(e + 1) % 3].position;
            const float length = std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
            if (!std::isfinite(length))
                continue;
            ++mSeen;
            if (mSample.size() < kCapacity) {
                mSample.push_back(length);
                continue;
            }
            // Algorithm R: the seen-th edge replaces a random one with probability capacity/seen.
            const std::uint64_t slot =
                    std::uniform_int_distribution<std::uint64_t>(0, mSeen - 1)(mRandom);
            if (slot < kCapacity)
                mSample[static_cast<std::size_t>(slot)] = length;
        }
    }
}

float EdgeSampler::median() const {
    if (mSample.empty())
        return 0.0f;
    std::vector<float> sorted = mSample;
    const auto middle = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2);
    std::nth_element(sorted.begin(), middle, sorted.end());
    return *middle;
}

Result<storage::PositionGrid> chooseGrid(
        std::array<float, 3> boundsMin,
        std::array<float, 3> boundsMax,
        const EdgeSampler& edges,
        float stepsPerMedianEdge) {
    FF_ASSERT(stepsPerMedianEdge > 0.0f);
    const float edge = edges.median();
    if (!(edge > 0.0f))
        return storage::PositionGrid::covering(
                boundsMin, boundsMax, storage::kDefaultPositionGridBits);
    auto grid = storage::PositionGrid::withStep(boundsMin, boundsMax, edge / stepsPerMedianEdge);
    if (grid.isOk())
        return grid;
    // More than 31 bits: the finest grid the codec holds over the extent instead.
    return storage::PositionGrid::covering(boundsMin, boundsMax, storage::kMaxPositionGridBits);
}

} // namespace ff::builder
