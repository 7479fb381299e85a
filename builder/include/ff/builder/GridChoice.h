#pragma once

// The position grid a prototype's clusters are quantized on (storage/ClusterCodec.h): a step
// that is a fixed fraction of its triangles' median edge, so the error follows the triangles
// and the bits grow with the extent over them, not with the extent alone (docs/methods.md §11:
// measured, median edge / 1024 keeps every surface within 8 bytes a triangle as a v2 file and
// stores no cluster wide). The median comes from a bounded, deterministic sample of the edges
// taken while the triangles stream in, so a prototype larger than memory costs 16 KiB for it.

#include <ff/storage/ClusterCodec.h>
#include <ff/storage/SceneFormat.h>
#include <ff/storage/Status.h>

#include <array>
#include <cstdint>
#include <random>
#include <span>
#include <vector>

namespace ff::builder {

/** Grid steps a median edge spans. */
inline constexpr float kGridStepsPerMedianEdge = 1024.0f;

/**
 * A uniform sample of at most kCapacity edge lengths of a triangle stream (reservoir sampling
 * with a fixed seed: the same stream gives the same sample). Not thread-safe.
 */
class EdgeSampler {
public:
    static constexpr std::size_t kCapacity = 4096;

    void add(std::span<const storage::PackedTriangle> triangles);
    /** The sample's median edge length; 0 when nothing was added. */
    [[nodiscard]] float median() const;
    [[nodiscard]] std::uint64_t edgesSeen() const noexcept { return mSeen; }
    [[nodiscard]] std::size_t sampleSize() const noexcept { return mSample.size(); }

private:
    std::vector<float> mSample;
    std::uint64_t mSeen = 0;
    std::mt19937_64 mRandom{0x5eed};
};

/**
 * The grid over [boundsMin, boundsMax] whose step is the sampled median edge /
 * `stepsPerMedianEdge` (> 0; kGridStepsPerMedianEdge, the builder's, unless measuring others).
 * Falls back to kDefaultPositionGridBits over the extent when there is no edge to measure, and to
 * kMaxPositionGridBits when the step would need more (a few tiny triangles in a vast prototype).
 * Errors: those of PositionGrid (non-finite bounds).
 */
[[nodiscard]] Result<storage::PositionGrid> chooseGrid(
        std::array<float, 3> boundsMin,
        std::array<float, 3> boundsMax,
        const EdgeSampler& edges,
        float stepsPerMedianEdge = kGridStepsPerMedianEdge);

} // namespace ff::builder
